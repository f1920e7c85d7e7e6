#pragma once
// The sand core's inner loops (internal to src/sand). They work on one scratch row of a tile and
// its 2-cell halo (kScratch doubles per row); cells outside the step's active set hold kWall.
// Every link flux is evaluated with one formula from the two cells' values, so the two cells of
// a link compute it bit for bit alike (x - y == -(y - x) in IEEE arithmetic), and sums are
// grouped symmetrically ((W + E) + (S + N)) + ((SW + NE) + (SE + NW)), so a configuration that is
// symmetric under the square's 8 symmetries stays so bit for bit.
#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

#include "sand/material.hpp"

namespace ps::sand::kernels {

inline constexpr int kScratch = 32 + 4;
inline constexpr double kWall = 1e30;  // the height of a cell that takes no part in a step
inline constexpr double kLive = 1e29;  // real heights are below this

// Excess e if it exceeds the rest tolerance eps, else 0.
inline double act(double e, double eps) {
  return e > eps ? e : 0.0;
}

// arctan(x) for x >= 0 (Abramowitz & Stegun 4.4.49 on [0, 1], |error| <= 2e-8 rad).
inline double fastAtan(double x) {
  const bool big = x > 1.0;
  const double inv = 1.0 / std::max(x, 1e-300);  // unconditional: keeps the loops branch-free
  const double y = big ? inv : x;
  const double z = y * y;
  const double p =
      y *
      (1.0 +
       z * (-0.3333314528 +
            z * (0.1999355085 +
                 z * (-0.1420889944 +
                      z * (0.1065626393 +
                           z * (-0.0752896400 +
                                z * (0.0429096138 + z * (-0.0161657367 + z * 0.0028662257))))))));
  return big ? 0.5 * std::numbers::pi - p : p;
}

// Paper 002's weight on a face: w = clamp((angle - alpha) / (pi/2 - alpha), 0, 1), with the face's
// slope angle atan((|dh| - cohesion)^+ / d); 0 at rest (w <= tolerance).
struct Repose {
  double alpha = 0, invRange = 0, cohesion = 0, rest = 0;
  static Repose of(const Material& m) {
    const double a = m.reposeDeg * std::numbers::pi / 180.0;
    return {a, 1.0 / (0.5 * std::numbers::pi - a), m.cohesion, m.reposeTolerance};
  }
};

inline double weight(double absDh, double invDist, const Repose& r) {
  const double slope = std::max(absDh - r.cohesion, 0.0) * invDist;
  double w = (fastAtan(slope) - r.alpha) * r.invRange;
  w = std::min(std::max(w, 0.0), 1.0);
  return w > r.rest ? w : 0.0;
}

// Volume per unit time from a cell at height h to a neighbour at hn across a face of
// conductance g (D l^2 L / d); 0 when either takes no part in the step.
inline double faceFlux(double h, double hn, double g, double invDist, const Repose& r) {
  const double d = h - hn;
  const double f = g * weight(std::abs(d), invDist, r) * d;
  return ((h < kLive) & (hn < kLive)) ? f : 0.0;
}

// Thermal pass 1, per row: t* thresholds (tan(talus) d + cohesion) and e* rest tolerances of the
// links W/E (H), to the row below (S) and above (N), diagonals below (SD) and above (ND);
// hra = c/2 * A.
struct ThermalRow1 {
  double tH, eH, tS, eS, tN, eN, tSD, eSD, tND, eND, hra;
};
// Thermal pass 2: the same thresholds, the receivers' caps A/8 (A/m for a pole) of this row (0),
// the row below (S) and above (N), and 1/A.
struct ThermalRow2 {
  double tH, eH, tS, eS, tN, eN, tSD, eSD, tND, eND, cap0, capS, capN, invA;
};

// s[c] for c in [1, kScratch - 1): the outflow scale c/2 * A * max_k e_k / sum_k e_k of a cell
// (volume per unit of excess), 0 where nothing exceeds the talus or the cell is a wall. Returns
// non-zero when some s > 0.
unsigned thermalPass1(const double* hm, const double* h0, const double* hp, double* s,
                      const ThermalRow1& k);
// out[c] for c in [2, kScratch - 2): h + (inflow - outflow) / A, a link's flux from a cell i to a
// lower neighbour j being min(s_i, cap_j) * e_ij (e_ij above the rest tolerance).
void thermalPass2(const double* hm, const double* h0, const double* hp, const double* sm,
                  const double* s0, const double* sp, double* out, const ThermalRow2& k);

// Explicit drift-diffusion, per row: face conductances g and inverse distances of the faces W/E
// (H), below (S) and above (N); dtInvA = dt / A.
struct DiffusionRow {
  double gH, invH, gS, invS, gN, invN, dtInvA;
};
// out[c] for c in [2, kScratch - 2): h - dt / A * (sum of face fluxes). Returns non-zero when a
// face moved material.
unsigned diffusionRow(const double* hm, const double* h0, const double* hp, double* out,
                      const DiffusionRow& k, const Repose& r);

// The octahedral chart's rows (sand_glued.cpp): kGluedRow cells from h0[0] (scratch rows, so
// h0[-1] and h0[kGluedRow] are the halo), each with its own constants (a tile's planes): the
// chords of the links W E S N SW SE NW NE (+inf where there is none), L / d and 1 / d of the
// axis links (0 where none), the area (0 where no cell: left as it was).
inline constexpr int kGluedRow = 32;
struct GluedRow {
  const double* d[8];
  const double* ratio[4];
  const double* inv[4];
  const double* area;
};
// s of the n cells from h0[0], as thermalPass1 (0 where no cell or a wall).
void gluedThermalPass1(const double* hm, const double* h0, const double* hp, double* s,
                       const GluedRow& g, double tanTalus, double cohesion, double tolerance,
                       double halfRate, int n = kGluedRow);
// The new heights, as thermalPass2 with every neighbour's receiver cap from c* (the caps'
// scratch rows).
void gluedThermalPass2(const double* hm, const double* h0, const double* hp, const double* sm,
                       const double* s0, const double* sp, const double* cm, const double* c0,
                       const double* cp, double* out, const GluedRow& g, double tanTalus,
                       double cohesion, double tolerance);
// Explicit diffusion, as diffusionRow with the conductance D l^2 (L / d) per face. Returns
// non-zero when a face moved material.
unsigned gluedDiffusionRow(const double* hm, const double* h0, const double* hp, double* out,
                           const GluedRow& g, double Dl2, double dt, const Repose& r);
// Explicit diffusion with each face weighed once (sand_glued_faces.cpp): gw[c] = (Dl2 ratio[c])
// weight(|a[c] - b[c]|, inv[c]) for c < n, the face's conductance times its weight, which both of
// its cells read (|x - y| == |y - x|, so either cell's view gives the same bits).
void gluedFaceWeights(const double* a, const double* b, const double* ratio, const double* inv,
                      double* gw, int n, double Dl2, const Repose& r);
// gluedDiffusionRow's result from the faces' gw: wW[c], wE[c], wS[c] and wN[c] those of cell c
// (where faces are shared, wW is wE - 1). Each face's flux is gw (h - hn), 0 unless both cells
// live: faceFlux's operations, so the same bits.
unsigned gluedDiffusionFromFaces(const double* hm, const double* h0, const double* hp, double* out,
                                 const double* wW, const double* wE, const double* wS,
                                 const double* wN, const double* area, double dt);

// Implicit Euler along one row of equal-area cells: (1 + k_{i-1} + k_i) x_i - k_{i-1} x_{i-1} -
// k_i x_{i+1} = b_i, with k[i] the scaled conductance of the face between i and i + 1 (and, when
// `circle`, k[n-1] the face between n - 1 and 0). x holds b on entry and the solution on return.
void solveRow(std::vector<double>& x, const std::vector<double>& k, bool circle,
              std::vector<double>& work);
// Implicit Euler along `lanes` columns at once (x[i * lanes + l]): (a_i + K_{i-1} + K_i) x_i -
// K_{i-1} x_{i-1} - K_i x_{i+1} = a_i b_i, a_i the cell area of row i, K[i * lanes + l] the face
// between rows i and i + 1.
void solveColumns(std::vector<double>& x, const std::vector<double>& K,
                  const std::vector<double>& a, int n, int lanes, std::vector<double>& work);
// The faces of one line of the glued charts (sand_semi_implicit_glued.cpp), cell p to p + 1 for
// p < n - 1 and, on a `circle`, n - 1 to 0: the weight w from the heights h and the link's 1 / d
// (inv), and K = dt (Dl2 ratio) w, ratio the link's L / d. Here so that it vectorises as the row
// kernels do (the same operations per face as a face taken alone).
void lineWeights(const double* h, const double* ratio, const double* inv, double* w, double* k,
                 int n, bool circle, double dt, double Dl2, const Repose& r);
// solveLine's open chain (not cyclic) on the n >= 2 cells of x, a with the faces K[i] between i
// and i + 1 (K[n - 1] not read), every K[i] > 0, in place: the same operations in the same order
// without its copies (cp: n doubles of scratch).
void solveChainInPlace(double* x, const double* a, const double* K, int n, double* cp);
// Implicit Euler along one line of cells with their own areas (the glued charts' lines,
// sand_semi_implicit_glued.cpp): (a_i + K_{i-1} + K_i) x_i - K_{i-1} x_{i-1} - K_i x_{i+1} =
// a_i b_i, K[i] the face between i and i + 1 and, when `cyclic`, K[n-1] the face between n - 1
// and 0 (Sherman-Morrison when every face is active; a face at rest cuts the circle). The matrix
// is symmetric with column sums a_i, so sum a_i x_i = sum a_i b_i up to rounding. x holds b on
// entry and the solution on return.
void solveLine(std::vector<double>& x, const std::vector<double>& a, const std::vector<double>& K,
               bool cyclic, std::vector<double>& work);

}  // namespace ps::sand::kernels
