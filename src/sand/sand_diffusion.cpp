#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/input_error.hpp"
#include "sand/sand_field_parts.hpp"

namespace ps::sand {

// ---------------------------------------------------------------------------------------------
// Drift-diffusion

double SandField::explicitBound(const Material& material, bool wholeGrid) const {
  material.validate();
  if (grid_.glued()) return gluedBound(material, wholeGrid, false);
  std::vector<std::uint8_t> rowUsed(std::size_t(m_) + 1, wholeGrid ? 1 : 0);
  bool polesUsed[2] = {wholeGrid, wholeGrid};
  if (!wholeGrid) {
    for (std::size_t t = 0; t < tiles_.size(); ++t) {
      if (!busy_[t] && !marked_[t]) continue;
      const int tv = int(t) / tilesU_;
      for (int v = tv * kT; v < std::min(m_ + 1, tv * kT + kT); ++v) rowUsed[std::size_t(v)] = 1;
    }
    if (grid_.sphere()) {
      for (int p = 0; p < 2; ++p) polesUsed[p] = poles_[p].busy || poles_[p].marked;
    }
  }
  return boundOverRows(material, rowUsed, polesUsed);
}

double SandField::boundOverRows(const Material& material, const std::vector<std::uint8_t>& rowUsed,
                                const bool polesUsed[2]) const {
  const double D = material.diffusion;
  if (!(D > 0.0)) return std::numeric_limits<double>::infinity();
  const double l2 = grid_.cellSize() * grid_.cellSize();
  auto gH = [&](int v) { return D * l2 * grid_.horizontalFace(v) / grid_.horizontal(v); };
  auto gV = [&](int v) { return D * l2 * grid_.verticalFace(v) / grid_.vertical(v); };
  double bound = std::numeric_limits<double>::infinity();
  for (int v = 0; v <= m_; ++v) {
    if (!rowUsed[std::size_t(v)]) continue;
    if (!grid_.ordinaryRow(v)) continue;
    double g = 2.0 * gH(v);
    if (v > 0) g += gV(v - 1);  // includes a ring cell's face to its pole
    if (v < m_) g += gV(v);
    bound = std::min(bound, grid_.area(v) / g);
  }
  if (grid_.sphere()) {
    for (int p = 0; p < 2; ++p) {
      if (!polesUsed[p]) continue;
      const int v = p == 0 ? 0 : m_;
      bound = std::min(bound, grid_.area(v) / (double(m_) * gV(p == 0 ? 0 : m_ - 1)));
    }
  }
  return bound;
}

void SandField::diffusionTile(int tu, int tv, const DiffusionTables& tb, double dt,
                              const PushForce* force, double* hs, std::uint8_t& busy) {
  gather(tu, tv, hs);
  const int v0 = tv * kT - 2;
  const bool sphere = grid_.sphere();
  unsigned any = 0;
  Tile& tile = *tiles_[std::size_t(tileIndex(tu, tv))];
  for (int lv = 0; lv < kT; ++lv) {
    const int r = lv + 2, v = v0 + r;
    double* out = tile.cur.get() + lv * kT - 2;  // in place: the scratch holds the old values
    if (!grid_.ordinaryRow(v)) {
      std::fill_n(out + 2, kT, kWall);
      continue;
    }
    const std::size_t i = std::size_t(v + 2);
    const kernels::DiffusionRow k{tb.gH[i], tb.invH[i], tb.gV[i - 1],   tb.invV[i - 1],
                                  tb.gV[i], tb.invV[i], dt * tb.invA[i]};
    const double* hm = hs + (r - 1) * kW;
    const double* h0 = hs + r * kW;
    const double* hp = hs + (r + 1) * kW;
    any |= kernels::diffusionRow(hm, h0, hp, out, k, tb.repose);
    if (sphere && (v == 1 || v == m_ - 1)) {
      const int p = v == 1 ? 0 : 1;
      const double* hq = p == 0 ? hm : hp;
      const double g = p == 0 ? k.gS : k.gN, inv = p == 0 ? k.invS : k.invN;
      for (int c = 2; c < kT + 2; ++c) {
        const int u = tu * kT + c - 2;
        if (u >= cols_) break;
        poleFlux_[p][std::size_t(u)] = kernels::faceFlux(h0[c], hq[c], g, inv, tb.repose);
      }
    }
    if (force) {
      for (int c = 2; c < kT + 2; ++c) {
        const int u = tu * kT + c - 2;
        if (u >= cols_) break;
        const double f = netDriftFlux(*force, tb.zetaInv, u, v);
        if (f != 0.0) {
          out[c] -= dt * f * tb.invA[i];
          any = 1;
        }
      }
    }
  }
  busy = any ? 1 : 0;
}

double SandField::driftFlux(const PushForce& force, double zetaInv, int ua, int va, int ub,
                            int vb) const {
  // Canonical order so that both cells of a face compute the same number.
  const bool swap = (vb < va) || (vb == va && ub < ua);
  if (swap) {
    std::swap(ua, ub);
    std::swap(va, vb);
  }
  const core::Chart& chart = grid_.chart();
  const Eigen::Vector3d pa = chart.position(ua, va, 0.0), pb = chart.position(ub, vb, 0.0);
  const double faceLength = va == vb ? grid_.horizontalFace(va) : grid_.verticalFace(va);
  const double flux = driftBetween(force, zetaInv, pa, pb, faceLength);
  return swap ? -flux : flux;
}

namespace {

// The push force's flux across the face pa-pb for a tangent offset `radial` from its foot: the
// (1 - t^2)^2 profile of paper 004 along the face's normal, on a sphere and a tube alike.
double profileFlux(const PushForce& force, double zetaInv, const Eigen::Vector3d& radial,
                   const Eigen::Vector3d& pa, const Eigen::Vector3d& pb, double faceLength,
                   double cellSize) {
  const double rho = radial.norm();
  if (!(rho < force.radius) || rho == 0.0) return 0.0;
  const Eigen::Vector3d n = (pb - pa).normalized();
  const double t = rho / force.radius;
  const double prof = (1.0 - t * t) * (1.0 - t * t);
  const double fn = force.strength * prof * radial.dot(n) / rho;
  return zetaInv * fn * cellSize * faceLength;
}

}  // namespace

// The drift flux from pa to pb across a face of that length.
double SandField::driftBetween(const PushForce& force, double zetaInv, const Eigen::Vector3d& pa,
                               const Eigen::Vector3d& pb, double faceLength) const {
  const core::Chart& chart = grid_.chart();
  const bool sphere = chart.sphereRadius() > 0.0;
  const Eigen::Vector3d mid = 0.5 * (pa + pb);
  Eigen::Vector3d foot = force.centre;
  if (grid_.tube()) return driftOnTube(force, zetaInv, pa, pb, faceLength);
  if (sphere) {
    foot = chart.sphereRadius() * force.centre.normalized();
  } else {
    foot.z() = 0.0;
  }
  // On a sphere only the hemisphere about the tool: at its antipode the tangent projection of
  // mid - foot vanishes too, and a ghost of the force pushed there.
  if (sphere && !(mid.dot(foot) > 0.0)) return 0.0;
  Eigen::Vector3d radial = mid - foot;
  if (sphere) {
    const Eigen::Vector3d up = mid.normalized();
    radial -= radial.dot(up) * up;
  }
  return profileFlux(force, zetaInv, radial, pa, pb, faceLength, grid_.cellSize());
}

// A tube has no centre to project through: the foot is the surface point under the tool
// (markForce), the radial direction is mid - foot in the tangent plane at mid, and only faces
// within the force's radius of the foot in 3D and facing its way take part (not the far wall of
// a cylinder, whose tangent projection of mid - foot can vanish, nor across a torus's hole).
double SandField::driftOnTube(const PushForce& force, double zetaInv, const Eigen::Vector3d& pa,
                              const Eigen::Vector3d& pb, double faceLength) const {
  if (!tubeFootValid_) return 0.0;
  const Eigen::Vector3d mid = 0.5 * (pa + pb);
  Eigen::Vector3d radial = mid - tubeFoot_;
  if (!(radial.norm() < force.radius)) return 0.0;
  const Eigen::Vector3d up = grid_.tubeNormal(mid);
  if (!(up.dot(tubeFootUp_) > 0.0)) return 0.0;
  radial -= radial.dot(up) * up;
  return profileFlux(force, zetaInv, radial, pa, pb, faceLength, grid_.cellSize());
}

double SandField::netDriftFlux(const PushForce& force, double zetaInv, int u, int v) const {
  const bool sphere = grid_.sphere();
  double f = 0.0;
  const int un[4] = {u - 1, u + 1, u, u};
  const int vn[4] = {v, v, v - 1, v + 1};
  for (int q = 0; q < 4; ++q) {
    int uu = un[q];
    if (sphere) uu = (uu + m_) % m_;
    if (!cellExists(uu, vn[q])) continue;
    f += driftFlux(force, zetaInv, u, v, uu, vn[q]);
  }
  return f;
}

void SandField::markForce(const PushForce& force) {
  const core::Chart& chart = grid_.chart();
  const auto foot = chart.inverse(force.centre);
  tubeFootValid_ = false;
  if (!foot) return;
  if (grid_.tube()) {
    // A box about the foot by the smallest chord in u and in v (the torus's inner equator, a
    // step round the tube), its columns wrapping the seam; where it reaches a torus's v seam
    // mark() adds its image across it (the rows it continues into).
    const double du = std::min(grid_.chord(0, 0, 1), grid_.chord(0, m_ / 2, 1));
    const double dv = std::min(grid_.chord(0, 1, 3), grid_.chord(0, m_ / 4, 3));
    const int ru = int(std::min(double(m_), std::ceil(force.radius / du))) + 2;
    const int rv = int(std::min(double(m_), std::ceil(force.radius / dv))) + 2;
    tubeFoot_ = chart.positionAt((*foot)(0), (*foot)(1), 0.0);
    tubeFootUp_ = grid_.tubeNormal(tubeFoot_);
    tubeFootValid_ = true;
    const int uc = int(std::lround((*foot)(0))), vc = int(std::lround((*foot)(1)));
    terrain::VertexBox r{uc - ru, uc + ru, std::max(0, vc - rv), std::min(m_, vc + rv)};
    if (2 * ru + 1 >= m_) r.uBegin = 0, r.uEnd = m_;
    mark(r);
    return;
  }
  if (grid_.glued()) {
    // A box about the foot at a quarter of lat-long's equatorial spacing (the octahedral
    // charts' smallest is above 0.3 of it), and its images across the folds and midlines
    // (mark() adds the folds'; the midlines' hold the disc's parts in other quadrants).
    const double spacing = 0.25 * 2.0 * std::numbers::pi * chart.sphereRadius() / m_;
    const int d = int(std::min(double(m_), std::ceil(force.radius / spacing))) + 2;
    const int uc = int(std::lround((*foot)(0))), vc = int(std::lround((*foot)(1)));
    const core::GridBox box{std::max(0, uc - d), std::min(m_, uc + d), std::max(0, vc - d),
                            std::min(m_, vc + d)};
    core::GridBox out[4];
    const int n = chart.gluedImages(box, true, out);
    for (int i = 0; i < n; ++i) mark({out[i].uBegin, out[i].uEnd, out[i].vBegin, out[i].vEnd});
    return;
  }
  const double spacingV = grid_.sphere() ? grid_.vertical(m_ / 2) : grid_.vertical(0);
  const int dv = int(std::ceil(force.radius / spacingV)) + 2;
  const int vc = int(std::lround((*foot)(1))), uc = int(std::lround((*foot)(0)));
  terrain::VertexBox r;
  r.vBegin = std::max(0, vc - dv);
  r.vEnd = std::min(m_, vc + dv);
  double minH = std::numeric_limits<double>::infinity();
  for (int v = r.vBegin; v <= r.vEnd; ++v) {
    if (grid_.ordinaryRow(v)) minH = std::min(minH, grid_.horizontal(v));
  }
  const int du = std::isfinite(minH) ? int(std::min(1e9, std::ceil(force.radius / minH))) + 2 : m_;
  if (grid_.sphere() && (2 * du + 1 >= m_ || r.vBegin == 0 || r.vEnd == m_)) {
    r.uBegin = 0;
    r.uEnd = m_;
  } else {
    r.uBegin = uc - du;
    r.uEnd = uc + du;
    if (!grid_.sphere()) {
      r.uBegin = std::max(0, r.uBegin);
      r.uEnd = std::min(m_, r.uEnd);
    }
  }
  mark(r);
}

const SandField::DiffusionTables& SandField::diffusionTables(const Material& material) {
  if (diffusionTables_ && diffusionMaterial_ == material) return *diffusionTables_;
  auto tables = std::make_unique<DiffusionTables>();
  DiffusionTables& tb = *tables;
  tb.repose = kernels::Repose::of(material);
  tb.zetaInv = material.frictionInverse;
  const std::size_t rows = std::size_t(m_) + 5;
  for (auto* a : {&tb.gH, &tb.gV, &tb.invH, &tb.invV, &tb.invA}) a->assign(rows, 0.0);
  const double Dl2 = material.diffusion * grid_.cellSize() * grid_.cellSize();
  for (int v = 0; v <= m_; ++v) {
    const std::size_t i = std::size_t(v + 2);
    tb.invA[i] = 1.0 / grid_.area(v);
    if (grid_.ordinaryRow(v)) {
      tb.gH[i] = Dl2 * grid_.horizontalFace(v) / grid_.horizontal(v);
      tb.invH[i] = 1.0 / grid_.horizontal(v);
    }
    if (v < m_ && (grid_.ordinaryRow(v) || grid_.ordinaryRow(v + 1))) {
      tb.gV[i] = Dl2 * grid_.verticalFace(v) / grid_.vertical(v);
      tb.invV[i] = 1.0 / grid_.vertical(v);
    }
  }
  diffusionTables_ = std::move(tables);
  diffusionMaterial_ = material;
  return *diffusionTables_;
}

StepReport SandField::diffusionStep(const Material& material, double dt, DiffusionScheme scheme,
                                    StepPolicy policy, const PushForce* force) {
  material.validate();
  if (!std::isfinite(dt) || !(dt > 0.0)) {
    throw core::InputError("diffusion time step dt = " + core::exactNumber(dt) +
                           " must be finite and > 0");
  }
  if (force) {
    if (!force->centre.allFinite() || !std::isfinite(force->radius) || !(force->radius > 0.0) ||
        !std::isfinite(force->strength)) {
      throw core::InputError("push force: centre, radius (> 0) and strength must be finite");
    }
    markForce(*force);
  }
  StepReport rep;
  rep.dt = dt;
  if (atRest()) return rep;
  if (grid_.glued() && !geometryEverywhere_) loadGeometryEverywhere();
  buildActiveSet(Predicate::kDiffusion, material);
  if (scheme == DiffusionScheme::kExplicit) {
    // The bound over the rows this step visits (the closed active set).
    std::vector<std::uint8_t> rowUsed(std::size_t(m_) + 1, 0);
    for (int t : tileList_) {
      const int tv = t / tilesU_;
      for (int v = tv * kT; v < std::min(m_ + 1, tv * kT + kT); ++v) rowUsed[std::size_t(v)] = 1;
    }
    const bool polesUsed[2] = {grid_.sphere() && poles_[0].inP, grid_.sphere() && poles_[1].inP};
    const double bound = grid_.glued() ? gluedBound(material, false, true)
                                       : boundOverRows(material, rowUsed, polesUsed);
    if (dt > bound) {
      if (policy == StepPolicy::kRefuse) {
        // Nothing has moved: forget the set this step would have visited.
        for (int t : tileList_) inP_[std::size_t(t)] = 0;
        tileList_.clear();
        if (grid_.sphere()) poles_[0].inP = poles_[1].inP = false;
        throw core::InputError("explicit diffusion time step dt = " + core::exactNumber(dt) +
                               " exceeds the stability bound " + core::exactNumber(bound) +
                               " (dt <= min A_i / (D l^2 sum L_f / d_f))");
      }
      if (policy == StepPolicy::kClamp) dt = bound;
    }
  }
  rep.dt = dt;
  const DiffusionTables& tb = diffusionTables(material);
  const bool sphere = grid_.sphere();
  if (sphere) {
    for (int p = 0; p < 2; ++p) {
      if (poles_[p].inP) std::fill(poleFlux_[p].begin(), poleFlux_[p].end(), 0.0);
    }
  }
  if (scheme == DiffusionScheme::kExplicit) {
    std::vector<std::uint8_t> busyOut(tileList_.size(), 0);
    const int n = int(tileList_.size());
#pragma omp parallel if (n >= kParallelTiles)
    {
      std::vector<double> hs(std::size_t(kW) * kW);
#pragma omp for schedule(static)
      for (int j = 0; j < n; ++j) tiles_[std::size_t(tileList_[std::size_t(j)])]->snapshot();
#pragma omp for schedule(dynamic, 1)
      for (int j = 0; j < n; ++j) {
        const int t = tileList_[std::size_t(j)];
        if (grid_.glued()) {
          diffusionGluedTile(t, tb, dt, force, hs.data(), busyOut[std::size_t(j)]);
        } else {
          diffusionTile(t % tilesU_, t / tilesU_, tb, dt, force, hs.data(),
                        busyOut[std::size_t(j)]);
        }
      }
    }
    for (int j = 0; j < n; ++j)
      busy_[std::size_t(tileList_[std::size_t(j)])] = busyOut[std::size_t(j)];
    if (sphere) {
      for (int p = 0; p < 2; ++p) {
        Pole& pole = poles_[std::size_t(p)];
        if (!pole.inP) continue;
        double in = 0.0;
        bool moved = false;
        for (double f : poleFlux_[p]) {
          in += f;
          moved |= f != 0.0;
        }
        pole.h += dt * in * (1.0 / grid_.area(p == 0 ? 0 : m_));
        pole.busy = moved;
      }
    }
  } else {
    semiImplicit(tb, dt, force);
  }
  finishStep(rep);
  return rep;
}

}  // namespace ps::sand
