#pragma once
#include <Eigen/Core>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <utility>
#include <vector>

#include "core/chart.hpp"
#include "sand/material.hpp"
#include "sand/sand_grid.hpp"
#include "terrain/vertex_box.hpp"

namespace ps::edit {
struct HeightChange;
}

namespace ps::sand {

// How an explicit diffusion step treats a requested time step above its stability bound.
enum class StepPolicy {
  kClamp,      // use the bound instead (the default)
  kRefuse,     // throw core::InputError naming dt and the bound
  kUnchecked,  // use it anyway: for demonstrating the blow-up past the bound (tests) only
};

enum class DiffusionScheme {
  kExplicit,      // forward Euler in flux form; dt <= the bound explicitBound() reports
  kSemiImplicit,  // LOD splitting: implicit Euler along rows, columns, then the polar caps
};

// The drift force of paper 002 (F in dh/dt = ... - div(F / zeta)): a tool pushing material away
// from its axis. |F| = strength (1 - (rho / radius)^2)^2 at distance rho from the axis (on the
// reference surface), directed away from it; the drift flux is zeta^-1 F in metres of height
// times reference cells per time unit (the paper's units: grid spacing 1).
struct PushForce {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();  // the tool, planet frame (m)
  double radius = 0.0;                               // m, > 0
  double strength = 0.0;                             // paper units, finite
};

// What one step did.
struct StepReport {
  std::size_t cells = 0;  // cells processed (the cell-steps this step cost)
  std::size_t tiles = 0;  // tiles processed
  double dt = 0.0;        // diffusion: the time step used
  bool moved = false;     // some material moved
};

// A double-precision working copy of a height array, kept in 32 x 32 tiles that are loaded when
// first needed, and the active set that decides which tiles a step visits (docs/SAND.md):
//
// * A step visits P = the tiles where material moved in the previous step, plus the tiles
//   marked as edited since, closed under "a link between a tile in P and one outside is
//   active" (checked with the real heights on the border; the pole points likewise). Outside P
//   nothing can move, so a step over P is bit for bit the step over the whole grid, in any
//   thread count. P is empty, and stays empty, once the terrain is at rest.
// * Each step is a Jacobi step (all tiles read the heights before the step: a tile is updated
//   in place after every tile of the step copied its two outer rows and columns), in parallel
//   over tiles (OpenMP). Material moves only along links between two cells of
//   P, and each link's flux is computed bit for bit identically on both sides, so the volume
//   sum_i A_i h_i changes only by the rounding of the double additions.
// * The float heights are written back by writeBack(), which returns the rectangle of floats
//   that changed (for Terrain::commitEdit).
//
// The float array must outlive the field. Heights changed behind the field's back must be
// reported with mark() (or found by resync()) once the field has written back.
class SandField {
 public:
  static constexpr int kTile = 32;

  SandField(std::shared_ptr<const core::Chart> chart, std::span<float> heights);
  ~SandField();
  SandField(const SandField&) = delete;
  SandField& operator=(const SandField&) = delete;

  const SandGrid& grid() const { return grid_; }

  // The floats in `region` changed outside the field: resident cells there are reloaded and the
  // region's tiles are visited by the next step.
  void mark(const terrain::VertexBox& region);
  // Every tile (and pole) is visited by the next step.
  void markAll();
  // Compares every resident cell with its float; reloads and marks those that differ. Returns
  // the number of cells reloaded. Call after writeBack().
  std::size_t resync();

  // Nothing pending: the next step would visit no tile.
  bool atRest() const;
  // Tiles (and poles) the next step starts from, before closure.
  std::size_t pendingTiles() const;

  // One thermal erosion step (paper 004) with the material's talus angle, rate, tolerance and
  // cohesion. Throws core::InputError for a material that fails validate().
  StepReport thermalStep(const Material& material);

  // One drift-diffusion step (paper 002, in flux form) of length dt. Explicit: the step is
  // stable for dt <= explicitBound(); policy says what happens above it. Semi-implicit: any dt.
  // A force (optional) is applied during the step; its tiles are visited.
  StepReport diffusionStep(const Material& material, double dt, DiffusionScheme scheme,
                           StepPolicy policy = StepPolicy::kClamp,
                           const PushForce* force = nullptr);
  // The explicit scheme's stability bound on dt over all rows (`wholeGrid`) or over the rows of
  // the tiles pending for the next step (before its closure, which may add rows; the step itself
  // uses the bound over the rows it actually visits):
  //   dt <= min over cells i of A_i / (D l^2 sum_faces L_f / d_f),
  // A_i the cell's area, L_f and d_f a face's length and the distance across it, l cellSize().
  // On a flat grid with dx = dy this is dt <= 1 / (4 D). +inf for D = 0.
  double explicitBound(const Material& material, bool wholeGrid = true) const;

  // Writes the floats of every tile changed since the last write-back (rounded to nearest,
  // clamped to +-limit; seam twins and whole pole rows) and returns the rectangle of floats
  // that changed (empty when none did). With `changes`, each float written is appended to it
  // with its height before and after (the undo journal's record of settling).
  terrain::VertexBox writeBack(double limit, std::vector<edit::HeightChange>* changes = nullptr);

  // Current height (double) of a grid vertex.
  double height(int u, int v) const;
  // Copies the current heights (double) into `out` ((m+1)^2, seam twins and pole rows filled).
  void copyHeights(std::vector<double>& out) const;
  // sum_i A_i h_i of the current (double) heights.
  double volume() const;

  // Writes back and forgets every resident tile that has nothing pending (frees memory).
  terrain::VertexBox release(double limit);
  std::size_t residentTiles() const;
  std::size_t residentBytes() const;

  // Work counters since construction.
  std::size_t totalCellSteps() const { return totalCellSteps_; }

 private:
  struct Tile;
  struct Pole;
  struct ThermalTables;
  struct DiffusionTables;
  enum class Predicate { kThermal, kDiffusion };

  int tileIndex(int tu, int tv) const { return tv * tilesU_ + tu; }
  // Calls f(u, v, i) for every ordinary cell of tile t, i its index in the tile's arrays
  // (sand_field_parts.hpp).
  template <class F>
  void forEachCellOf(int t, F&& f) const;
  bool cellExists(int u, int v) const;
  // Tile of a neighbour column (wrapping on the sphere); -1 outside.
  int wrapTileU(int tu) const;
  Tile& loadTile(int t);
  void loadPole(int p);
  double value(int u, int v) const;  // real height of an existing cell (resident or float)
  double poleValue(int p) const;

  // Builds P (inP_ flags, tileList_) from busy/marked and closes it under active links.
  void buildActiveSet(Predicate pred, const Material& material);
  const ThermalTables& thermalTables(const Material& material);
  const DiffusionTables& diffusionTables(const Material& material);
  double boundOverRows(const Material& material, const std::vector<std::uint8_t>& rowUsed,
                       const bool polesUsed[2]) const;
  bool linkActive(Predicate pred, int ua, int va, int ub, int vb, const Material& material) const;
  bool poleLinkActive(Predicate pred, int p, int u, const Material& material) const;
  void markForce(const PushForce& force);
  void finishStep(StepReport& rep);

  void gather(int tu, int tv, double* scratch) const;
  void thermalTile(int tu, int tv, const ThermalTables& tb, double* hs, double* ss,
                   std::uint8_t& busy);
  void diffusionTile(int tu, int tv, const DiffusionTables& tb, double dt, const PushForce* force,
                     double* hs, std::uint8_t& busy);
  double driftFlux(const PushForce& force, double zetaInv, int ua, int va, int ub, int vb) const;
  // The force's drift out of cell (u, v) through its four faces.
  double netDriftFlux(const PushForce& force, double zetaInv, int u, int v) const;

  // The octahedral chart (sand_glued.cpp): per-cell geometry, a one-cell halo read across the
  // glued sides through the chart's gluing, the thermal step in two passes over the tiles.
  void markRegion(const terrain::VertexBox& region);
  void loadGeometry(Tile& tile, int t);
  // A tile away from the glued sides while only thermal steps have run: no Tile::geo (its step
  // reads Tile::thermalPlanes), only the tiles it links to, its 8 neighbours.
  void loadInnerLinks(Tile& tile, int t) const;
  // Tile::geo for every resident tile, and for every tile loaded from now on (the diffusion
  // steps read it on every tile).
  void loadGeometryEverywhere();
  // Fills the kGeoPlanes planes of tile t's cells into geo; returns min A / sum_f (L_f / d_f).
  double computeGeometry(int t, double* geo) const;
  // The source of scratch position (r, c) of tile (tu, tv) (a one-cell halo, the grid continued
  // across the glued sides to the canonical vertex): its tile and index there, or false
  // (outside the grid).
  bool gluedSource(int tu, int tv, int r, int c, int& tile, int& local) const;
  void gatherGlued(int tu, int tv, double* hs, double* ss) const;
  void loadHalo(Tile& tile, int t) const;
  bool gluedBorderTile(int tu, int tv) const;
  double gluedTileBound(int t) const;  // min A / sum_f (L_f / d_f) over tile t's cells
  double gluedBound(const Material& material, bool wholeGrid, bool visited) const;
  bool gluedLinkActive(Predicate pred, int u, int v, int k, const Material& material) const;
  void gluedActiveSetLinks(int t, Predicate pred, const Material& material,
                           const std::function<void(int)>& add);
  StepReport thermalStepGlued(const Material& material);
  void thermalGluedPass1(int t, const Material& material, double* hs);
  void thermalGluedPass2(int t, const Material& material, double* hs, double* ss,
                         std::uint8_t& busy);
  // A tile away from the glued sides in one pass, as lat-long's: the s of its cells and their
  // ring from a two-cell halo, then its heights (the links arrive in grid order there, so the
  // ring's s has the bits its own tile computes).
  void thermalGluedInner(int t, const Material& material, double* hs, double* ss,
                         std::uint8_t& busy);
  void loadThermalPlanes(Tile& tile, int t) const;
  void diffusionGluedTile(int t, const DiffusionTables& tb, double dt, const PushForce* force,
                          double* hs, std::uint8_t& busy);
  // Explicit diffusion with each face of the tile weighed once (sand_glued_faces.cpp) where
  // the tile's planes give both cells of the face the same conductance and 1 / d; false when
  // no row of the tile has such faces.
  bool gluedFacesShared(Tile& tile) const;
  unsigned diffusionGluedFaces(Tile& tile, const double* hs, const DiffusionTables& tb, double Dl2,
                               double dt) const;
  double netDriftFluxGlued(const PushForce& force, double zetaInv, int u, int v) const;
  double driftBetween(const PushForce& force, double zetaInv, const Eigen::Vector3d& pa,
                      const Eigen::Vector3d& pb, double faceLength) const;
  double driftOnTube(const PushForce& force, double zetaInv, const Eigen::Vector3d& pa,
                     const Eigen::Vector3d& pb, double faceLength) const;

  // The semi-implicit step (sand_semi_implicit.cpp) and its parts, in order: next = cur, the
  // force's drift (explicit), the rows' implicit solves, the columns', the polar caps'.
  void semiImplicit(const DiffusionTables& tb, double dt, const PushForce* force);
  // Per tile of P: whether the step moved sand there (set from several threads).
  using BusyFlags = std::unique_ptr<std::atomic<std::uint8_t>[]>;
  struct RowRun;
  struct ColumnRun;
  void setBusy(BusyFlags& busy, int u, int v) const;
  void copyCurToNext();
  void applyDrift(const PushForce& force, const DiffusionTables& tb, double dt, BusyFlags& busy);
  std::vector<std::pair<int, int>> tileRunsOfRow(int tv) const;
  std::vector<RowRun> rowRuns() const;
  void solveRows(const std::vector<RowRun>& runs, const DiffusionTables& tb, double dt,
                 BusyFlags& busy);
  std::vector<ColumnRun> columnRuns() const;
  void solveColumns(const std::vector<ColumnRun>& runs, const DiffusionTables& tb, double dt,
                    BusyFlags& busy);
  void solvePolarCaps(const DiffusionTables& tb, double dt, BusyFlags& busy);
  // The glued charts' semi-implicit step (sand_semi_implicit_glued.cpp): the same sub-steps
  // along lines of canonical cells continued across the folds and seams (GluedLines).
  struct GluedLines;
  const GluedLines& gluedLines();
  void fillLineGeometry(GluedLines& lines) const;
  void semiImplicitGlued(const DiffusionTables& tb, double dt, const PushForce* force);
  void applyDriftGlued(const PushForce& force, const DiffusionTables& tb, double dt,
                       BusyFlags& busy);
  void solveGluedLines(int dir, const DiffusionTables& tb, double dt, BusyFlags& busy);
  std::vector<int> gluedLinesToSolve(int dir) const;
  struct LineRunScratch;  // one line's cells read in line order, and a solve's scratch
  void solveGluedLine(LineRunScratch& s, int n, bool circle, BusyFlags& busy) const;
  void solveGluedRun(LineRunScratch& s, bool circle, BusyFlags& busy) const;
  void solveGluedChain(LineRunScratch& s, int first, int c) const;
  void readLine(LineRunScratch& s, int n) const;
  void writeLine(const LineRunScratch& s, int n);

  SandGrid grid_;
  std::span<float> heights_;
  int m_, cols_, tilesU_, tilesV_;
  std::vector<std::unique_ptr<Tile>> tiles_;
  std::unique_ptr<Pole[]> poles_;  // [0] south (v = 0), [1] north (v = m); sphere only
  std::vector<std::uint8_t> busy_, marked_, inP_;
  std::vector<int> tileList_;
  std::vector<double> poleFlux_[2];  // per column: net flux into the pole this step
  std::size_t totalCellSteps_ = 0;
  // m^3 the floats written so far hold less than the doubles did (writeBack's error diffusion).
  double carry_ = 0.0;
  bool geometryEverywhere_ = false;  // glued: Tile::geo on every tile (see loadInnerLinks)
  // A tube's push force (markForce): the surface point under the tool and its normal, set
  // before a step's tiles run.
  Eigen::Vector3d tubeFoot_ = Eigen::Vector3d::Zero(), tubeFootUp_ = Eigen::Vector3d::Zero();
  bool tubeFootValid_ = false;
  // Per-row constants of the last material used (rebuilt when it changes).
  std::unique_ptr<ThermalTables> thermalTables_;
  std::unique_ptr<DiffusionTables> diffusionTables_;
  std::unique_ptr<GluedLines> gluedLines_;  // built on the first glued semi-implicit step
  Material thermalMaterial_, diffusionMaterial_;
};

}  // namespace ps::sand
