#include "tin/dynamic_tin.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "core/input_error.hpp"
#include "tin/dynamic_tin_impl.hpp"

// Never refined: the sand TIN uses the triangulation without the mesher's bases (tin/cdt.hpp).

namespace ps::tin {

static_assert(sizeof(lean::Tds::Face) == 56,
              "the lean face: three vertices, three neighbours, three constraint flags");

DynamicTin::DynamicTin(std::span<const Eigen::Vector3d> points) : impl_(std::make_unique<Impl>()) {
  for (std::size_t k = 0; k < points.size(); ++k) {
    const Eigen::Vector3d& p = points[k];
    if (!p.allFinite())
      throw core::InputError("TIN: point " + std::to_string(k) +
                             " has a coordinate that is not finite");
  }
  lean::FaceHandle hint;
  for (const Eigen::Vector3d& p : points) {
    const std::size_t before = impl_->cdt.number_of_vertices();
    const lean::VertexHandle v = impl_->cdt.insert(Point(p.x(), p.y()), hint);
    if (impl_->cdt.number_of_vertices() > before) {
      v->info().index = kUnnumbered;
      impl_->number(v);
    }
    v->info().height = p.z();  // a repeated point: the last height wins
    hint = v->face();
  }
  if (impl_->cdt.dimension() != 2)
    throw core::InputError("TIN: the points (" + std::to_string(points.size()) +
                           ") do not span an area");
  impl_->hint = impl_->cdt.finite_vertices_begin();
}

DynamicTin::~DynamicTin() = default;
DynamicTin::DynamicTin(DynamicTin&&) noexcept = default;
DynamicTin& DynamicTin::operator=(DynamicTin&&) noexcept = default;

std::size_t DynamicTin::vertexCount() const {
  return impl_->cdt.number_of_vertices();
}
std::size_t DynamicTin::triangleCount() const {
  return impl_->cdt.number_of_faces();
}
std::uint64_t DynamicTin::topologyEpoch() const {
  return impl_->epoch;
}

std::size_t DynamicTin::constrainedEdgeCount() const {
  return impl_->generations.size();
}

std::size_t DynamicTin::memoryBytes() const {
  const auto& tds = impl_->cdt.tds();
  return tds.vertices().capacity() * sizeof(lean::Tds::Vertex) +
         tds.faces().capacity() * sizeof(lean::Tds::Face) +
         impl_->handles.capacity() * sizeof(lean::VertexHandle) +
         impl_->freeNumbers.capacity() * sizeof(Vertex) +
         impl_->generations.size() *
             (sizeof(std::uint64_t) + sizeof(std::uint32_t) + 2 * sizeof(void*)) +
         impl_->generations.bucket_count() * sizeof(void*);
}

DynamicTin::Slots DynamicTin::slots() const {
  const auto& tds = impl_->cdt.tds();
  return {tds.vertices().capacity(), tds.vertices().size(), tds.faces().capacity(),
          tds.faces().size()};
}

bool DynamicTin::alive(Vertex v) const {
  return v < impl_->handles.size() && impl_->handles[v] != lean::VertexHandle();
}

Eigen::Vector2d DynamicTin::position(Vertex v) const {
  return xyOf(impl_->handle(v)->point());
}
double DynamicTin::height(Vertex v) const {
  return impl_->handle(v)->info().height;
}
void DynamicTin::setHeight(Vertex v, double h) {
  impl_->handle(v)->info().height = h;
}

bool DynamicTin::onHull(Vertex v) const {
  const lean::VertexHandle& h = impl_->handle(v);
  auto c = impl_->cdt.incident_vertices(h), done = c;
  do
    if (impl_->cdt.is_infinite(c)) return true;
  while (++c != done);
  return false;
}

void DynamicTin::neighbours(Vertex v, std::vector<Vertex>& out) const {
  out.clear();
  auto c = impl_->cdt.incident_vertices(impl_->handle(v)), done = c;
  do
    if (!impl_->cdt.is_infinite(c)) out.push_back(c->info().index);
  while (++c != done);
}

void DynamicTin::neighbourhood(Vertex v, std::vector<Neighbour>& out) const {
  out.clear();
  auto c = impl_->cdt.incident_vertices(impl_->handle(v)), done = c;
  do
    if (!impl_->cdt.is_infinite(c))
      out.push_back({c->info().index, xyOf(c->point()), c->info().height});
  while (++c != done);
}

double DynamicTin::weight(Vertex v) const {
  double area2 = 0;
  auto f = impl_->cdt.incident_faces(impl_->handle(v)), done = f;
  do
    if (!impl_->cdt.is_infinite(f))
      area2 += signedArea2(f->vertex(0)->point(), f->vertex(1)->point(), f->vertex(2)->point());
  while (++f != done);
  return area2 / 6.0;
}

std::vector<DynamicTin::Vertex> DynamicTin::vertices() const {
  std::vector<Vertex> out;
  out.reserve(vertexCount());
  for (Vertex v = 0; v < impl_->handles.size(); ++v)
    if (impl_->handles[v] != lean::VertexHandle()) out.push_back(v);
  return out;
}

DynamicTin::Vertex DynamicTin::insert(const Eigen::Vector2d& p, double h) {
  if (!std::isfinite(h) || !p.allFinite())
    throw std::invalid_argument("DynamicTin: a vertex that is not finite");
  Impl& m = *impl_;
  const Point q(p.x(), p.y());
  lean::Cdt::Locate_type lt;
  int li = 0;
  const lean::FaceHandle f = m.cdt.locate(q, lt, li, m.startFace());
  if (lt == lean::Cdt::OUTSIDE_CONVEX_HULL || lt == lean::Cdt::OUTSIDE_AFFINE_HULL)
    throw std::invalid_argument("DynamicTin: a vertex outside the domain");
  // A constrained edge split by the new vertex: both halves keep its generation.
  lean::VertexHandle splitA, splitB;
  std::uint32_t splitGeneration = 0;
  if (lt == lean::Cdt::EDGE && f->is_constrained(li)) {
    splitA = f->vertex(lean::Cdt::ccw(li));
    splitB = f->vertex(lean::Cdt::cw(li));
    const auto it = m.generations.find(edgeKey(splitA->info().index, splitB->info().index));
    if (it != m.generations.end()) {
      splitGeneration = it->second;
      m.generations.erase(it);
    }
  }
  const std::size_t before = m.cdt.number_of_vertices();
  const lean::VertexHandle v = m.cdt.insert(q, lt, f, li);
  ++m.epoch;
  if (m.cdt.number_of_vertices() > before) v->info().index = kUnnumbered;
  const Vertex id = m.number(v);
  v->info().height = h;
  if (splitA != lean::VertexHandle()) {
    m.generations[edgeKey(splitA->info().index, id)] = splitGeneration;
    m.generations[edgeKey(id, splitB->info().index)] = splitGeneration;
  }
  m.hint = v;
  return id;
}

DynamicTin::Vertex DynamicTin::insertOnSurface(const Eigen::Vector2d& p) {
  const double h = heightAt(p);
  if (std::isnan(h)) throw std::invalid_argument("DynamicTin: a vertex outside the domain");
  return insert(p, h);
}

void DynamicTin::constrain(Vertex a, Vertex b, std::uint32_t generation) {
  Impl& m = *impl_;
  const lean::VertexHandle va = m.handle(a), vb = m.handle(b);
  if (va == vb) return;
  const std::size_t before = m.cdt.number_of_vertices();
  m.cdt.insert_constraint(va, vb);
  ++m.epoch;
  if (m.cdt.number_of_vertices() != before) {
    // It crossed a constrained edge (the caller should have freed it): the crossings are
    // vertices of both, with the height of the new edge there.
    for (auto v = m.cdt.finite_vertices_begin(); v != m.cdt.finite_vertices_end(); ++v) {
      if (v->info().index != kUnnumbered && v->info().index < m.handles.size() &&
          m.handles[v->info().index] == lean::VertexHandle(v))
        continue;
      v->info().index = kUnnumbered;
      m.number(v);
      const Eigen::Vector2d pa = xyOf(va->point()), pb = xyOf(vb->point());
      const double t = (xyOf(v->point()) - pa).dot(pb - pa) / (pb - pa).squaredNorm();
      v->info().height = (1 - t) * va->info().height + t * vb->info().height;
    }
  }
  m.tagPath(va, vb, generation);
}

std::size_t DynamicTin::freeConstraintsNear(
    const Eigen::Vector2d& centre, double radius,
    std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>>* freed) {
  Impl& m = *impl_;
  std::vector<lean::FaceHandle> faces;
  m.facesTouching(centre, radius, faces);
  std::vector<std::pair<lean::VertexHandle, lean::VertexHandle>> edges;
  std::unordered_set<std::uint64_t> seen;
  for (const lean::FaceHandle& f : faces)
    for (int k = 0; k < 3; ++k) {
      if (!f->is_constrained(k)) continue;
      const lean::VertexHandle a = f->vertex(lean::Cdt::ccw(k)), b = f->vertex(lean::Cdt::cw(k));
      if (pointSegmentDistance(centre, xyOf(a->point()), xyOf(b->point())) <= radius &&
          seen.insert(edgeKey(a->info().index, b->info().index)).second)
        edges.emplace_back(a, b);
    }
  std::size_t count = 0;
  for (const auto& [a, b] : edges) {
    lean::FaceHandle f;
    int i = 0;
    if (!m.cdt.is_edge(a, b, f, i) || !f->is_constrained(i)) continue;
    if (freed)
      freed->emplace_back(Eigen::Vector3d(a->point().x(), a->point().y(), a->info().height),
                          Eigen::Vector3d(b->point().x(), b->point().y(), b->info().height));
    m.cdt.remove_constrained_edge(f, i);
    ++m.epoch;
    m.generations.erase(edgeKey(a->info().index, b->info().index));
    ++count;
  }
  return count;
}

std::uint32_t DynamicTin::generation(Vertex a, Vertex b) const {
  const auto it = impl_->generations.find(edgeKey(a, b));
  return it == impl_->generations.end() ? kNoVertex : it->second;
}

bool DynamicTin::remove(Vertex id, double* volumeChange, bool restoreVolume) {
  Impl& m = *impl_;
  const lean::VertexHandle v = m.handle(id);
  if (onHull(id)) return false;
  std::vector<lean::VertexHandle> link;
  double before = 0;
  auto f = m.cdt.incident_faces(v), fdone = f;
  do {
    const int i = f->index(v);
    link.push_back(f->vertex(lean::Cdt::ccw(i)));
    before += faceVolume(f);
    // Freed without flips: the edges at v leave with it, and the hole is re-filled
    // constrained-Delaunay, so nothing else changes.
    if (f->is_constrained(lean::Cdt::cw(i))) {
      m.generations.erase(edgeKey(id, f->vertex(lean::Cdt::ccw(i))->info().index));
      f->set_constraint(lean::Cdt::cw(i), false);
      const lean::FaceHandle g = f->neighbor(lean::Cdt::cw(i));
      g->set_constraint(g->index(f), false);
    }
  } while (++f != fdone);
  const Point p = v->point();
  m.cdt.remove(v);
  ++m.epoch;
  m.handles[id] = lean::VertexHandle();
  m.freeNumbers.push_back(id);
  m.hint = link.front();

  // The hole's new faces: from the face over the removed point, not across the rim (sets:
  // after many removals a vertex's link can run to hundreds).
  std::unordered_set<std::uint64_t> rim;
  for (std::size_t k = 0; k < link.size(); ++k)
    rim.insert(edgeKey(link[k]->info().index, link[(k + 1) % link.size()]->info().index));
  double after = 0;
  std::unordered_set<const void*> seen;
  std::vector<lean::FaceHandle> stack{m.cdt.locate(p, link.front()->face())};
  while (!stack.empty()) {
    const lean::FaceHandle g = stack.back();
    stack.pop_back();
    if (m.cdt.is_infinite(g) || !seen.insert(&*g).second) continue;
    after += faceVolume(g);
    for (int k = 0; k < 3; ++k)
      if (!rim.count(edgeKey(g->vertex(lean::Cdt::ccw(k))->info().index,
                             g->vertex(lean::Cdt::cw(k))->info().index)))
        stack.push_back(g->neighbor(k));
  }
  const double change = after - before;
  if (volumeChange) *volumeChange = change;
  if (!restoreVolume) return true;
  double rimWeight = 0;
  for (const lean::VertexHandle& u : link) rimWeight += weight(u->info().index);
  if (rimWeight > 0 && change != 0)
    for (const lean::VertexHandle& u : link) u->info().height -= change / rimWeight;
  return true;
}

double DynamicTin::volume() const {
  long double sum = 0;
  for (auto f = impl_->cdt.finite_faces_begin(); f != impl_->cdt.finite_faces_end(); ++f)
    sum += faceVolume(f);
  return double(sum);
}

bool DynamicTin::isValid() const {
  return validityProblem().empty();
}

std::string DynamicTin::validityProblem() const {
  const Impl& m = *impl_;
  if (!m.cdt.is_valid()) {
    // Which part: the data structure, a face's orientation, or the Delaunay property of an
    // edge that is not constrained (what the constrained Delaunay triangulation's check adds).
    if (!m.cdt.tds().is_valid())
      return "CGAL's check of the triangulation failed: the data structure";
    for (auto f = m.cdt.finite_faces_begin(); f != m.cdt.finite_faces_end(); ++f)
      if (CGAL::orientation(f->vertex(0)->point(), f->vertex(1)->point(), f->vertex(2)->point()) !=
          CGAL::LEFT_TURN)
        return "CGAL's check of the triangulation failed: a face not counter-clockwise at (" +
               std::to_string(f->vertex(0)->point().x()) + ", " +
               std::to_string(f->vertex(0)->point().y()) + ")";
    for (auto e = m.cdt.finite_edges_begin(); e != m.cdt.finite_edges_end(); ++e) {
      if (m.cdt.is_constrained(*e)) continue;
      const lean::FaceHandle f = e->first, g = f->neighbor(e->second);
      if (m.cdt.is_infinite(f) || m.cdt.is_infinite(g)) continue;
      const lean::VertexHandle opposite = g->vertex(m.cdt.mirror_index(f, e->second));
      if (m.cdt.side_of_oriented_circle(f, opposite->point(), true) == CGAL::ON_POSITIVE_SIDE) {
        const Point a = f->vertex(lean::Cdt::ccw(e->second))->point(),
                    b = f->vertex(lean::Cdt::cw(e->second))->point();
        return "CGAL's check of the triangulation failed: edge (" + std::to_string(a.x()) + ", " +
               std::to_string(a.y()) + ")-(" + std::to_string(b.x()) + ", " +
               std::to_string(b.y()) + ") is free and not Delaunay, length " +
               std::to_string(std::hypot(a.x() - b.x(), a.y() - b.y()));
      }
    }
    return "CGAL's check of the triangulation failed";
  }
  for (auto v = m.cdt.finite_vertices_begin(); v != m.cdt.finite_vertices_end(); ++v) {
    if (!std::isfinite(v->info().height))
      return "vertex " + std::to_string(v->info().index) + " has a height that is not finite";
    if (v->info().index >= m.handles.size() || m.handles[v->info().index] != lean::VertexHandle(v))
      return "a vertex at (" + std::to_string(v->point().x()) + ", " +
             std::to_string(v->point().y()) + ") has no number";
  }
  std::size_t constrained = 0;
  for (auto e = m.cdt.finite_edges_begin(); e != m.cdt.finite_edges_end(); ++e) {
    if (!m.cdt.is_constrained(*e)) continue;
    ++constrained;
    const Vertex a = e->first->vertex(lean::Cdt::ccw(e->second))->info().index;
    const Vertex b = e->first->vertex(lean::Cdt::cw(e->second))->info().index;
    if (!m.generations.count(edgeKey(a, b)))
      return "constrained edge " + std::to_string(a) + "-" + std::to_string(b) +
             " has no generation";
  }
  if (constrained != m.generations.size())
    return std::to_string(m.generations.size()) + " generations for " +
           std::to_string(constrained) + " constrained edges";
  return "";
}

Tin DynamicTin::toTin() const {
  Tin out;
  std::vector<std::uint32_t> index(impl_->handles.size(), kUnnumbered);
  for (Vertex v = 0; v < impl_->handles.size(); ++v) {
    if (impl_->handles[v] == lean::VertexHandle()) continue;
    index[v] = std::uint32_t(out.xy.size());
    out.xy.push_back(position(v));
    out.h.push_back(height(v));
  }
  for (auto f = impl_->cdt.finite_faces_begin(); f != impl_->cdt.finite_faces_end(); ++f)
    out.triangles.push_back({index[f->vertex(0)->info().index], index[f->vertex(1)->info().index],
                             index[f->vertex(2)->info().index]});
  return out;
}

}  // namespace ps::tin
