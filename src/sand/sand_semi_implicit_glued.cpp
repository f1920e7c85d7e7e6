// Semi-implicit (LOD) diffusion on the glued charts (the octahedral chart, both mappings; the
// torus and the cylinder): lat-long's scheme (sand_semi_implicit.cpp) with its rows and columns
// replaced by lines of canonical cells continued across the folds and seams. Along W/E links,
// then along S/N links, each line is one implicit Euler system in the area-weighted form
//     A_i x_i + sum_f K_f (x_i - x_j) = A_i b_i,   K_f = dt D l^2 (L_f / d_f) w_f >= 0,
// with the explicit scheme's per-cell constants (Tile::geo) and weights from the heights before
// the step: symmetric, diagonally dominant M-matrices, so each sub-step keeps sum A_i x_i and
// obeys a maximum principle at any dt. A cell is one unknown however many twins it has; a line
// that comes back to its first cell is a circle (Sherman-Morrison, as lat-long's rows round the
// sphere). Diffusion has axis links only (the diagonals are thermal erosion's), so the two
// directions hold every link of the explicit operator, each once.
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

#include "sand/sand_field_parts.hpp"

namespace ps::sand {

namespace {
constexpr std::size_t kCells = std::size_t(kT) * kT;
constexpr std::uint32_t kNone = std::uint32_t(-1);
constexpr int kLocalBits = 10;  // a cell's index in its tile (GluedLines::Direction::cells)
static_assert(kT * kT == 1 << kLocalBits);
}  // namespace

// Walks every cell's lines: from a cell, back to an end of its line (or round to itself: a
// circle), then forwards from there, each step taking the link of the direction's two that does
// not lead back. A cone point keeps one of the two links that reach its one neighbour, so it
// ends its line (the middle rows and columns fold onto themselves there); the cylinder's rims
// end its columns.
const SandField::GluedLines& SandField::gluedLines() {
  if (gluedLines_) return *gluedLines_;
  auto lines = std::make_unique<GluedLines>();
  const core::GridSize& g = grid_.grid();
  const std::uint32_t side = std::uint32_t(m_ + 1);
  for (int d = 0; d < 2; ++d) {
    GluedLines::Direction& dir = lines->dir[std::size_t(d)];
    dir.byRow.assign(std::size_t(m_) + 1, {});
    std::vector<std::uint8_t> seen(g.count(), 0);
    // The next cell from `cur` along direction d, not `prev`, and the link there.
    auto next = [&](std::uint32_t prev, std::uint32_t cur, int& kOut) -> std::uint32_t {
      const int u = int(cur % side), v = int(cur / side);
      for (int k = 2 * d; k < 2 * d + 2; ++k) {
        const core::GridPoint n = grid_.neighbour(u, v, k);
        if (n.u < 0) continue;
        const std::uint32_t j = std::uint32_t(g.index(n.u, n.v));
        if (j == prev) continue;
        kOut = k;
        return j;
      }
      return kNone;
    };
    for (int v = 0; v <= m_; ++v) {
      for (int u = 0; u <= m_; ++u) {
        const std::uint32_t s = std::uint32_t(g.index(u, v));
        if (!grid_.isCell(u, v) || seen[s]) continue;
        int k = 0;
        if (next(kNone, s, k) == kNone) continue;  // no link this way: no line
        // Back to an end, or round to s.
        std::uint32_t prev = s, cur = next(kNone, s, k), first = s;
        for (std::size_t guard = 0; cur != s; ++guard) {
          const std::uint32_t n = next(prev, cur, k);
          if (n == kNone) {
            first = cur;
            break;
          }
          if (guard > g.count()) throw std::logic_error("glued lines: a walk does not end");
          prev = cur, cur = n;
        }
        const int l = int(dir.start.size());
        dir.start.push_back(std::uint32_t(dir.cells.size()));
        bool circle = false;
        prev = kNone, cur = first;
        for (;;) {
          if (seen[cur]) {
            throw std::logic_error("glued lines: cell " + std::to_string(cur) +
                                   " lies on two lines of the " + grid_.chart().name() + " chart");
          }
          seen[cur] = 1;
          dir.cells.push_back(cur);
          dir.link.push_back(0);
          auto& rows = dir.byRow[d == 0 ? cur / side : cur % side];
          if (rows.empty() || rows.back() != l) rows.push_back(l);
          const std::uint32_t n = next(prev, cur, k);
          if (n == kNone) break;
          dir.link.back() = std::uint8_t(k);
          if (n == first) {
            circle = true;
            break;
          }
          prev = cur, cur = n;
        }
        dir.cyclic.push_back(circle ? 1 : 0);
      }
    }
    dir.start.push_back(std::uint32_t(dir.cells.size()));
    // Each cell as its tile and its index there (what the solves look up), not its grid index.
    for (std::uint32_t& c : dir.cells) {
      const int u = int(c % side), v = int(c / side);
      c = (std::uint32_t(tileIndex(u / kT, v / kT)) << kLocalBits) |
          std::uint32_t((v % kT) * kT + u % kT);
    }
  }
  fillLineGeometry(*lines);
  gluedLines_ = std::move(lines);
  return *gluedLines_;
}

std::size_t SandField::GluedLines::bytes() const {
  std::size_t b = 0;
  for (const Direction& d : dir) {
    b += d.cells.size() * sizeof(std::uint32_t) + d.link.size() + d.cyclic.size() +
         d.start.size() * sizeof(std::uint32_t) +
         (d.area.size() + d.ratio.size() + d.inv.size()) * sizeof(double);
    for (const std::vector<int>& r : d.byRow) b += r.size() * sizeof(int);
  }
  return b;
}

// Each line cell's area, L / d and 1 / d from its tile's geometry planes (the same function
// Tile::geo is filled by, so the same bits), tile by tile.
void SandField::fillLineGeometry(GluedLines& lines) const {
  const std::size_t nTiles = tiles_.size();
  std::vector<std::uint32_t> posOf[2];
  for (int d = 0; d < 2; ++d) {
    GluedLines::Direction& dir = lines.dir[d];
    const std::size_t n = dir.cells.size();
    dir.area.assign(n, 0.0), dir.ratio.assign(n, 0.0), dir.inv.assign(n, 0.0);
    posOf[d].assign(nTiles * kCells, kNone);
    for (std::size_t p = 0; p < n; ++p) posOf[d][dir.cells[p]] = std::uint32_t(p);
  }
#pragma omp parallel
  {
    std::vector<double> scratch(std::size_t(kGeoPlanes) * kCells);
#pragma omp for schedule(dynamic, 8)
    for (int t = 0; t < int(nTiles); ++t) {
      const Tile* tile = tiles_[std::size_t(t)].get();
      const double* geo = tile && tile->geo ? tile->geo.get() : scratch.data();
      if (geo == scratch.data()) computeGeometry(t, scratch.data());
      for (int d = 0; d < 2; ++d) {
        GluedLines::Direction& dir = lines.dir[d];
        for (std::size_t i = 0; i < kCells; ++i) {
          const std::uint32_t p = posOf[d][(std::size_t(t) << kLocalBits) | i];
          if (p == kNone) continue;
          const std::size_t k = dir.link[p];
          dir.area[p] = geo[std::size_t(kGeoArea) * kCells + i];
          dir.ratio[p] = geo[(std::size_t(kGeoRatio) + k) * kCells + i];
          dir.inv[p] = geo[(std::size_t(kGeoInv) + k) * kCells + i];
        }
      }
    }
  }
}

void SandField::semiImplicitGlued(const DiffusionTables& tb, double dt, const PushForce* force) {
  auto busy = std::make_unique<std::atomic<std::uint8_t>[]>(tiles_.size());
  for (int t : tileList_) busy[std::size_t(t)].store(0, std::memory_order_relaxed);
  gluedLines();
  copyCurToNext();
  if (force) applyDriftGlued(*force, tb, dt, busy);
  solveGluedLines(0, tb, dt, busy);
  solveGluedLines(1, tb, dt, busy);
  for (int t : tileList_) {
    busy_[std::size_t(t)] = busy[std::size_t(t)].load(std::memory_order_relaxed);
    Tile& tile = *tiles_[std::size_t(t)];
    std::swap(tile.cur, tile.next);
  }
}

// The force's drift, explicit, per cell with its own area.
void SandField::applyDriftGlued(const PushForce& force, const DiffusionTables& tb, double dt,
                                BusyFlags& busy) {
  for (int t : tileList_) {
    Tile& tile = *tiles_[std::size_t(t)];
    const double* area = tile.geo.get() + std::size_t(kGeoArea) * kCells;
    forEachCellOf(t, [&](int u, int v, std::size_t i) {
      const double f = netDriftFluxGlued(force, tb.zetaInv, u, v);
      if (f != 0.0) {
        tile.next[i] -= dt * f * (1.0 / area[i]);
        busy[std::size_t(t)].store(1, std::memory_order_relaxed);
      }
    });
  }
}

// One line's cells in line order: right-hand side x (the solution on return) and height before
// the step (0 for a cell outside P), whether in P, its area (the line's static geometry), then
// each face's w and K; and the scratch of its runs' solves.
struct SandField::LineRunScratch {
  const GluedLines::Direction* L = nullptr;
  int b = 0;  // the line's first cell in L->cells
  const double* area = nullptr;
  std::vector<double> x, h, w, k;
  std::vector<std::uint8_t> in;
  std::vector<double> xs, as, ks, work;
  std::vector<int> run;  // positions in the line
  void resize(int n) {
    for (std::vector<double>* v : {&x, &h, &w, &k}) v->resize(std::size_t(n));
    in.resize(std::size_t(n));
  }
  std::size_t tileOf(int p) const { return L->cells[std::size_t(b + p)] >> kLocalBits; }
};

// The lines of direction `dir` with a cell in P, in the order of their rows (columns).
std::vector<int> SandField::gluedLinesToSolve(int dir) const {
  const GluedLines::Direction& L = gluedLines_->dir[std::size_t(dir)];
  const int nTiles = dir == 0 ? tilesV_ : tilesU_;
  std::vector<std::uint8_t> bandUsed(std::size_t(nTiles), 0), lineUsed(L.cyclic.size(), 0);
  for (int t : tileList_) bandUsed[std::size_t(dir == 0 ? t / tilesU_ : t % tilesU_)] = 1;
  std::vector<int> todo;
  for (int b = 0; b < nTiles; ++b) {
    if (!bandUsed[std::size_t(b)]) continue;
    for (int r = b * kT; r < std::min(m_ + 1, b * kT + kT); ++r) {
      for (int l : L.byRow[std::size_t(r)]) {
        if (!lineUsed[std::size_t(l)]) lineUsed[std::size_t(l)] = 1, todo.push_back(l);
      }
    }
  }
  return todo;
}

// One line (s.x .. s.k read), solved over its runs of cells in P: a circle is cut after a cell
// outside P (if any); runs are the cells in P between.
void SandField::solveGluedLine(LineRunScratch& s, int n, bool circle, BusyFlags& busy) const {
  auto inside = [&](int p) { return s.in[std::size_t(p)] != 0; };
  int first = 0;
  bool whole = false;
  if (circle) {
    while (first < n && inside(first)) ++first;
    whole = first == n;
    first = whole ? 0 : first + 1;
  }
  s.run.clear();
  // Positions first, first + 1, .. round the circle (no division a cell).
  for (int q = 0, i = first == n ? 0 : first; q < n; ++q, i = i + 1 < n ? i + 1 : 0) {
    if (!inside(i)) {
      solveGluedRun(s, false, busy);
      s.run.clear();
      continue;
    }
    s.run.push_back(i);
  }
  solveGluedRun(s, whole, busy);
}

// The run of line positions s.run (a circle when `circle`: then the whole line): each stretch of
// active faces apart, so that cells at rest keep their bits and a step over P is the step over
// the grid.
void SandField::solveGluedRun(LineRunScratch& s, bool circle, BusyFlags& busy) const {
  const std::vector<int>& run = s.run;
  const int n = int(run.size());
  if (n < 2) return;
  const int faces = circle ? n : n - 1;
  int rest = -1;  // a face at rest, if any
  std::size_t marked = ~std::size_t(0);
  auto mark = [&](std::size_t t) {
    if (t == marked) return;
    busy[t].store(1, std::memory_order_relaxed);
    marked = t;
  };
  std::size_t tileHere = s.tileOf(run[0]);
  for (int i = 0; i < faces; ++i) {
    const std::size_t tileNext = s.tileOf(run[std::size_t(i + 1 < n ? i + 1 : 0)]);
    if (s.w[std::size_t(run[std::size_t(i)])] > 0.0) {
      mark(tileHere);
      mark(tileNext);
    } else if (rest < 0) {
      rest = i;
    }
    tileHere = tileNext;
  }
  if (circle && rest < 0) {
    // The whole circle, every face active: its arrays are the system.
    s.as.assign(s.area, s.area + n);
    kernels::solveLine(s.x, s.as, s.k, true, s.work);
    return;
  }
  // From just after a face at rest (a circle's), chains of active faces: the run's cells
  // st + j0 .. st + j (mod n).
  const int st = circle ? rest + 1 : 0;
  int j0 = 0;
  for (int j = 0, i = st < n ? st : st - n; j < n; ++j, i = i + 1 < n ? i + 1 : 0) {
    const bool face = j + 1 < n && (circle || i + 1 < n);
    if (face && s.k[std::size_t(run[std::size_t(i)])] > 0.0) continue;
    if (j > j0) solveGluedChain(s, st + j0, j - j0 + 1);
    j0 = j + 1;
  }
}

// The open chain of the run's cells first .. first + c - 1 (mod the run's length), every face
// between them active: kernels::solveLine's open chain.
void SandField::solveGluedChain(LineRunScratch& s, int first, int c) const {
  const std::vector<int>& run = s.run;
  const int n = int(run.size());
  auto at = [&](int t) { return std::size_t(run[std::size_t((first + t) % n)]); };
  const std::size_t p0 = at(0);
  s.work.resize(std::size_t(c));
  if (at(c - 1) == p0 + std::size_t(c - 1)) {
    // Consecutive cells of the line: solved where they lie.
    kernels::solveChainInPlace(s.x.data() + p0, s.area + p0, s.k.data() + p0, c, s.work.data());
    return;
  }
  s.xs.resize(std::size_t(c));
  s.as.resize(std::size_t(c));
  s.ks.resize(std::size_t(c));
  for (int t = 0; t < c; ++t) {
    s.xs[std::size_t(t)] = s.x[at(t)];
    s.as[std::size_t(t)] = s.area[at(t)];
    s.ks[std::size_t(t)] = t + 1 < c ? s.k[at(t)] : 0.0;
  }
  kernels::solveLine(s.xs, s.as, s.ks, false, s.work);
  for (int t = 0; t < c; ++t) s.x[at(t)] = s.xs[std::size_t(t)];
}

// The lines of direction `dir` with a cell in P, each solved over its runs of cells in P (a
// cell outside P is a wall, as in the explicit step), next -> next. Each line's heights are read
// into arrays in line order (its geometry lies in line order already), its faces' weights
// computed over them (the arctangents in one loop), then its runs solved on those arrays.
void SandField::solveGluedLines(int dir, const DiffusionTables& tb, double dt, BusyFlags& busy) {
  const GluedLines::Direction& L = gluedLines_->dir[std::size_t(dir)];
  const std::vector<int> todo = gluedLinesToSolve(dir);
  const kernels::Repose rep = tb.repose;
  const double Dl2 = diffusionMaterial_.diffusion * grid_.cellSize() * grid_.cellSize();
#pragma omp parallel if (int(tileList_.size()) >= kParallelTiles)
  {
    LineRunScratch s;
    s.L = &L;
#pragma omp for schedule(dynamic, 4)
    for (int j = 0; j < int(todo.size()); ++j) {
      const int l = todo[std::size_t(j)];
      s.b = int(L.start[std::size_t(l)]);
      const int n = int(L.start[std::size_t(l) + 1]) - s.b;
      const bool circle = L.cyclic[std::size_t(l)] != 0;
      s.resize(n);
      s.area = L.area.data() + s.b;
      readLine(s, n);
      kernels::lineWeights(s.h.data(), L.ratio.data() + s.b, L.inv.data() + s.b, s.w.data(),
                           s.k.data(), n, circle, dt, Dl2, rep);
      solveGluedLine(s, n, circle, busy);
      writeLine(s, n);
    }
  }
}

// The line's cells' right-hand sides and heights (0 outside P), a tile's pointers looked up once
// for each stretch of the line within it.
void SandField::readLine(LineRunScratch& s, int n) const {
  const std::uint32_t* cells = s.L->cells.data() + s.b;
  // Local pointers: the byte stores to s.in would otherwise reload the vectors' a cell.
  double* __restrict x = s.x.data();
  double* __restrict h = s.h.data();
  std::uint8_t* __restrict inside = s.in.data();
  std::size_t t = ~std::size_t(0);
  const double *next = nullptr, *cur = nullptr;
  std::uint8_t in = 0;
  for (int q = 0; q < n; ++q) {
    const std::uint32_t c = cells[q];
    if ((c >> kLocalBits) != t) {
      t = c >> kLocalBits;
      in = inP_[t];
      if (in) next = tiles_[t]->next.get(), cur = tiles_[t]->cur.get();
    }
    const std::size_t li = c & ((1u << kLocalBits) - 1u), p = std::size_t(q);
    inside[p] = in;
    x[p] = in ? next[li] : 0.0;
    h[p] = in ? cur[li] : 0.0;
  }
}

// The solution back into the cells in P.
void SandField::writeLine(const LineRunScratch& s, int n) {
  const std::uint32_t* cells = s.L->cells.data() + s.b;
  for (int q = 0; q < n; ++q) {
    if (!s.in[std::size_t(q)]) continue;
    const std::uint32_t c = cells[q];
    tiles_[c >> kLocalBits]->next[c & ((1u << kLocalBits) - 1u)] = s.x[std::size_t(q)];
  }
}

}  // namespace ps::sand
