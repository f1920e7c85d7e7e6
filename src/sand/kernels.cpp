// No trapping math lets GCC if-convert the loops that divide (the results are the same IEEE
// operations); set for the whole file so that the inline helpers of kernels.hpp inline into the
// kernels (functions with differing optimize attributes do not inline into each other).
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC optimize("no-trapping-math")
#endif
#include "sand/kernels.hpp"

// The row kernels are compiled twice on x86-64 (baseline SSE2 and AVX2, picked at load time by
// an ifunc). Neither clone may use FMA: contracting a * b + c would round differently in the two
// and break bit-for-bit reproducibility across machines (AVX2 alone brings no FMA).
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && \
    !defined(__SANITIZE_ADDRESS__)
#define PS_SAND_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define PS_SAND_CLONES
#endif

namespace ps::sand::kernels {

namespace {
constexpr int kW = kScratch;
}

PS_SAND_CLONES
unsigned thermalPass1(const double* hm, const double* h0, const double* hp, double* s,
                      const ThermalRow1& k) {
  const double tH = k.tH, eH = k.eH, tS = k.tS, eS = k.eS, tN = k.tN, eN = k.eN;
  const double tSD = k.tSD, eSD = k.eSD, tND = k.tND, eND = k.eND, hra = k.hra;
  unsigned any = 0;
  for (int c = 1; c < kW - 1; ++c) {
    const double h = h0[c];
    const double eW = act(h - h0[c - 1] - tH, eH);
    const double eE = act(h - h0[c + 1] - tH, eH);
    const double eSo = act(h - hm[c] - tS, eS);
    const double eNo = act(h - hp[c] - tN, eN);
    const double eSW = act(h - hm[c - 1] - tSD, eSD);
    const double eSE = act(h - hm[c + 1] - tSD, eSD);
    const double eNW = act(h - hp[c - 1] - tND, eND);
    const double eNE = act(h - hp[c + 1] - tND, eND);
    const double E = ((eW + eE) + (eSo + eNo)) + ((eSW + eNE) + (eSE + eNW));
    const double mx = std::max(std::max(std::max(eW, eE), std::max(eSo, eNo)),
                               std::max(std::max(eSW, eNE), std::max(eSE, eNW)));
    const double q = hra * mx / (E > 0.0 ? E : 1.0);
    const double sv = ((E > 0.0) & (h < kLive)) ? q : 0.0;
    s[c] = sv;
    any |= unsigned(sv > 0.0);
  }
  return any;
}

PS_SAND_CLONES
void thermalPass2(const double* hm, const double* h0, const double* hp, const double* sm,
                  const double* s0, const double* sp, double* out, const ThermalRow2& k) {
  const double tH = k.tH, eH = k.eH, tS = k.tS, eS = k.eS, tN = k.tN, eN = k.eN;
  const double tSD = k.tSD, eSD = k.eSD, tND = k.tND, eND = k.eND;
  const double cap0 = k.cap0, capS = k.capS, capN = k.capN, invA = k.invA;
  // A link carries material one way at most (e_ij + e_ji = -2 threshold <= 0): its flux is
  // act(|d| - t) times min(s_sender, cap_receiver), signed by which side is higher. The same
  // operands as evaluating both directions, so both cells of a link get it bit for bit.
  auto link = [](double d, double t, double e, double sOther, double capOther, double sSelf,
                 double capSelf) {
    const double a = act(std::abs(d) - t, e);
    const double coef = d > 0.0 ? -std::min(sSelf, capOther) : std::min(sOther, capSelf);
    return coef * a;
  };
  for (int c = 2; c < kW - 2; ++c) {
    const double h = h0[c], si = s0[c];
    const double nW = link(h - h0[c - 1], tH, eH, s0[c - 1], cap0, si, cap0);
    const double nE = link(h - h0[c + 1], tH, eH, s0[c + 1], cap0, si, cap0);
    const double nS = link(h - hm[c], tS, eS, sm[c], capS, si, cap0);
    const double nN = link(h - hp[c], tN, eN, sp[c], capN, si, cap0);
    const double nSW = link(h - hm[c - 1], tSD, eSD, sm[c - 1], capS, si, cap0);
    const double nSE = link(h - hm[c + 1], tSD, eSD, sm[c + 1], capS, si, cap0);
    const double nNW = link(h - hp[c - 1], tND, eND, sp[c - 1], capN, si, cap0);
    const double nNE = link(h - hp[c + 1], tND, eND, sp[c + 1], capN, si, cap0);
    const double net = ((nW + nE) + (nS + nN)) + ((nSW + nNE) + (nSE + nNW));
    out[c] = h + net * invA;
  }
}

PS_SAND_CLONES
unsigned diffusionRow(const double* hm, const double* h0, const double* hp, double* out,
                      const DiffusionRow& k, const Repose& r) {
  const Repose rr = r;
  const double gH = k.gH, invH = k.invH, gS = k.gS, invS = k.invS, gN = k.gN, invN = k.invN;
  const double dtInvA = k.dtInvA;
  unsigned any = 0;
  for (int c = 2; c < kW - 2; ++c) {
    const double h = h0[c];
    const double fW = faceFlux(h, h0[c - 1], gH, invH, rr);
    const double fE = faceFlux(h, h0[c + 1], gH, invH, rr);
    const double fS = faceFlux(h, hm[c], gS, invS, rr);
    const double fN = faceFlux(h, hp[c], gN, invN, rr);
    const double net = (fW + fE) + (fS + fN);
    out[c] = h - dtInvA * net;
    any |= unsigned(((std::abs(fW) + std::abs(fE)) + (std::abs(fS) + std::abs(fN))) > 0.0);
  }
  return any;
}

// The glued kernels read their operands through restrict-qualified copies of the pointers and
// capture scalars by value: without that GCC cannot rule out that `out` or `s` alias one of
// the 17 constant planes (too many pairs to check at run time) and leaves the loops scalar
// (4.6x lat-long's time per thermal cell-step; docs/SAND.md, "Where the octahedral chart's time
// went"). The operations are the same, lane by lane: the results are bit for bit the same.
namespace {
struct GluedPlanes {
  const double* __restrict d0;
  const double* __restrict d1;
  const double* __restrict d2;
  const double* __restrict d3;
  const double* __restrict d4;
  const double* __restrict d5;
  const double* __restrict d6;
  const double* __restrict d7;
  const double* __restrict area;
};
}  // namespace

PS_SAND_CLONES
void gluedThermalPass1(const double* __restrict hm, const double* __restrict h0,
                       const double* __restrict hp, double* __restrict s, const GluedRow& g,
                       double T, double coh, double eta, double halfRate, int n) {
  const GluedPlanes p{g.d[0], g.d[1], g.d[2], g.d[3], g.d[4], g.d[5], g.d[6], g.d[7], g.area};
  auto ex = [T, coh, eta](double h, double hn, double d) {
    return act(h - hn - (T * d + coh), eta * T * d);
  };
  for (int c = 0; c < n; ++c) {
    const double h = h0[c];
    const double eW = ex(h, h0[c - 1], p.d0[c]), eE = ex(h, h0[c + 1], p.d1[c]);
    const double eS = ex(h, hm[c], p.d2[c]), eN = ex(h, hp[c], p.d3[c]);
    const double eSW = ex(h, hm[c - 1], p.d4[c]), eSE = ex(h, hm[c + 1], p.d5[c]);
    const double eNW = ex(h, hp[c - 1], p.d6[c]), eNE = ex(h, hp[c + 1], p.d7[c]);
    const double E = ((eW + eE) + (eS + eN)) + ((eSW + eNE) + (eSE + eNW));
    const double mx = std::max(std::max(std::max(eW, eE), std::max(eS, eN)),
                               std::max(std::max(eSW, eNE), std::max(eSE, eNW)));
    const double q = (halfRate * p.area[c]) * mx / (E > 0.0 ? E : 1.0);
    s[c] = ((E > 0.0) & (p.area[c] > 0.0) & (h < kLive)) ? q : 0.0;
  }
}

PS_SAND_CLONES
void gluedThermalPass2(const double* __restrict hm, const double* __restrict h0,
                       const double* __restrict hp, const double* __restrict sm,
                       const double* __restrict s0, const double* __restrict sp,
                       const double* __restrict cm, const double* __restrict c0,
                       const double* __restrict cp, double* __restrict out, const GluedRow& g,
                       double T, double coh, double eta) {
  const GluedPlanes p{g.d[0], g.d[1], g.d[2], g.d[3], g.d[4], g.d[5], g.d[6], g.d[7], g.area};
  // thermalPass2's link: act(|d| - t) times min(s_sender, cap_receiver), signed by which side
  // is higher; the same operands from both cells.
  auto link = [T, coh, eta](double h, double hn, double dist, double sOther, double capOther,
                            double sSelf, double capSelf) {
    const double d = h - hn;
    const double a = act(std::abs(d) - (T * dist + coh), eta * T * dist);
    const double coef = d > 0.0 ? -std::min(sSelf, capOther) : std::min(sOther, capSelf);
    return coef * a;
  };
  for (int c = 0; c < kGluedRow; ++c) {
    const double h = h0[c], si = s0[c], capSelf = c0[c];
    const double nW = link(h, h0[c - 1], p.d0[c], s0[c - 1], c0[c - 1], si, capSelf);
    const double nE = link(h, h0[c + 1], p.d1[c], s0[c + 1], c0[c + 1], si, capSelf);
    const double nS = link(h, hm[c], p.d2[c], sm[c], cm[c], si, capSelf);
    const double nN = link(h, hp[c], p.d3[c], sp[c], cp[c], si, capSelf);
    const double nSW = link(h, hm[c - 1], p.d4[c], sm[c - 1], cm[c - 1], si, capSelf);
    const double nSE = link(h, hm[c + 1], p.d5[c], sm[c + 1], cm[c + 1], si, capSelf);
    const double nNW = link(h, hp[c - 1], p.d6[c], sp[c - 1], cp[c - 1], si, capSelf);
    const double nNE = link(h, hp[c + 1], p.d7[c], sp[c + 1], cp[c + 1], si, capSelf);
    const double net = ((nW + nE) + (nS + nN)) + ((nSW + nNE) + (nSE + nNW));
    const double A = p.area[c];
    const double next = h + net * (1.0 / (A > 0.0 ? A : 1.0));
    out[c] = A > 0.0 ? next : out[c];
  }
}

PS_SAND_CLONES
unsigned gluedDiffusionRow(const double* __restrict hm, const double* __restrict h0,
                           const double* __restrict hp, double* __restrict out, const GluedRow& g,
                           double Dl2, double dt, const Repose& r) {
  const Repose rr = r;
  const double* __restrict r0 = g.ratio[0];
  const double* __restrict r1 = g.ratio[1];
  const double* __restrict r2 = g.ratio[2];
  const double* __restrict r3 = g.ratio[3];
  const double* __restrict i0 = g.inv[0];
  const double* __restrict i1 = g.inv[1];
  const double* __restrict i2 = g.inv[2];
  const double* __restrict i3 = g.inv[3];
  const double* __restrict area = g.area;
  unsigned any = 0;
  for (int c = 0; c < kGluedRow; ++c) {
    const double h = h0[c];
    const double fW = faceFlux(h, h0[c - 1], Dl2 * r0[c], i0[c], rr);
    const double fE = faceFlux(h, h0[c + 1], Dl2 * r1[c], i1[c], rr);
    const double fS = faceFlux(h, hm[c], Dl2 * r2[c], i2[c], rr);
    const double fN = faceFlux(h, hp[c], Dl2 * r3[c], i3[c], rr);
    const double net = (fW + fE) + (fS + fN);
    const double A = area[c];
    const double dtInvA = dt * (1.0 / (A > 0.0 ? A : 1.0));
    out[c] = A > 0.0 ? h - dtInvA * net : out[c];
    any |= unsigned(((std::abs(fW) + std::abs(fE)) + (std::abs(fS) + std::abs(fN))) > 0.0);
  }
  return any;
}

PS_SAND_CLONES
void gluedFaceWeights(const double* __restrict a, const double* __restrict b,
                      const double* __restrict ratio, const double* __restrict inv,
                      double* __restrict gw, int n, double Dl2, const Repose& r) {
  const Repose rr = r;
  for (int c = 0; c < n; ++c) gw[c] = (Dl2 * ratio[c]) * weight(std::abs(a[c] - b[c]), inv[c], rr);
}

PS_SAND_CLONES
unsigned gluedDiffusionFromFaces(const double* __restrict hm, const double* __restrict h0,
                                 const double* __restrict hp, double* __restrict out,
                                 const double* __restrict wW, const double* __restrict wE,
                                 const double* __restrict wS, const double* __restrict wN,
                                 const double* __restrict area, double dt) {
  // faceFlux with g * weight known: (g w) d, 0 unless both cells live.
  auto flux = [](double h, double hn, double gw) {
    const double f = gw * (h - hn);
    return ((h < kLive) & (hn < kLive)) ? f : 0.0;
  };
  unsigned any = 0;
  for (int c = 0; c < kGluedRow; ++c) {
    const double h = h0[c];
    const double fW = flux(h, h0[c - 1], wW[c]);
    const double fE = flux(h, h0[c + 1], wE[c]);
    const double fS = flux(h, hm[c], wS[c]);
    const double fN = flux(h, hp[c], wN[c]);
    const double net = (fW + fE) + (fS + fN);
    const double A = area[c];
    const double dtInvA = dt * (1.0 / (A > 0.0 ? A : 1.0));
    out[c] = A > 0.0 ? h - dtInvA * net : out[c];
    any |= unsigned(((std::abs(fW) + std::abs(fE)) + (std::abs(fS) + std::abs(fN))) > 0.0);
  }
  return any;
}

void lineWeights(const double* __restrict h, const double* __restrict ratio,
                 const double* __restrict inv, double* __restrict w, double* __restrict k, int n,
                 bool circle, double dt, double Dl2, const Repose& r) {
  const Repose rr = r;
  for (int p = 0; p + 1 < n; ++p) {
    const double wp = weight(std::abs(h[p] - h[p + 1]), inv[p], rr);
    w[p] = wp;
    k[p] = dt * (Dl2 * ratio[p]) * wp;
  }
  if (circle && n > 0) {
    const double wp = weight(std::abs(h[n - 1] - h[0]), inv[n - 1], rr);
    w[n - 1] = wp;
    k[n - 1] = dt * (Dl2 * ratio[n - 1]) * wp;
  }
}

namespace {

// Thomas algorithm for (1 + k_{i-1} + k_i) x_i - k_{i-1} x_{i-1} - k_i x_{i+1} = d_i, faces
// k(i) between i and i + 1 for i < n - 1; x holds d on entry.
template <class K>
void thomas(double* x, int n, const K& k, double* cp) {
  double kPrev = 0.0, cPrev = 0.0;
  for (int i = 0; i < n; ++i) {
    const double kr = i + 1 < n ? k(i) : 0.0;
    const double denom = (1.0 + kPrev + kr) + kPrev * cPrev;  // sub-diagonal is -kPrev
    cp[i] = -kr / denom;
    x[i] = (x[i] + kPrev * (i > 0 ? x[i - 1] : 0.0)) / denom;
    cPrev = cp[i];
    kPrev = kr;
  }
  for (int i = n - 2; i >= 0; --i) x[i] -= cp[i] * x[i + 1];
}

}  // namespace

void solveRow(std::vector<double>& x, const std::vector<double>& k, bool circle,
              std::vector<double>& work) {
  const int n = int(x.size());
  if (n == 0) return;
  const int faces = circle ? n : n - 1;
  bool any = false;
  int cut = -1;
  for (int i = 0; i < faces; ++i) {
    any |= k[std::size_t(i)] > 0.0;
    if (cut < 0 && !(k[std::size_t(i)] > 0.0)) cut = i;
  }
  if (!any) return;
  work.resize(std::size_t(3 * n + 2));
  double* cp = work.data();
  if (!circle) {
    thomas(
        x.data(), n, [&](int i) { return k[std::size_t(i)]; }, cp);
    return;
  }
  if (cut >= 0) {
    // A face at rest cuts the circle: solve the open chain starting just after it.
    double* y = work.data() + n;
    const int s = cut + 1;
    for (int j = 0; j < n; ++j) y[j] = x[std::size_t((s + j) % n)];
    thomas(
        y, n, [&](int j) { return k[std::size_t((s + j) % n)]; }, cp);
    for (int j = 0; j < n; ++j) x[std::size_t((s + j) % n)] = y[j];
    return;
  }
  // Every face active: cyclic system by Sherman-Morrison, A = A' + u v^T with the corner
  // entries -k[n-1] moved into the diagonal (gamma = -b_0).
  const double kc = k[std::size_t(n - 1)];
  double* z = work.data() + n;
  double* zc = work.data() + 2 * n;
  const double b0 = 1.0 + kc + k[0];
  const double gamma = -b0;
  // A' differs from the open chain in its first and last diagonal entries.
  auto solveModified = [&](double* v) {
    // Diagonal: b_0 - gamma at 0, b_{n-1} - kc * kc / gamma at n - 1, others as usual.
    double kPrev = 0.0, cPrev = 0.0;
    for (int i = 0; i < n; ++i) {
      const double kl = i > 0 ? k[std::size_t(i - 1)] : kc;
      const double kr = i + 1 < n ? k[std::size_t(i)] : kc;
      double b = 1.0 + kl + kr;
      if (i == 0) b -= gamma;
      if (i == n - 1) b -= kc * kc / gamma;
      const double sub = i > 0 ? kPrev : 0.0;
      const double sup = i + 1 < n ? kr : 0.0;
      const double denom = b + sub * cPrev;
      zc[i] = -sup / denom;
      v[i] = (v[i] + sub * (i > 0 ? v[i - 1] : 0.0)) / denom;
      cPrev = zc[i];
      kPrev = sup;
    }
    for (int i = n - 2; i >= 0; --i) v[i] -= zc[i] * v[i + 1];
  };
  solveModified(x.data());
  for (int i = 0; i < n; ++i) z[i] = 0.0;
  z[0] = gamma;
  z[n - 1] = -kc;
  solveModified(z);
  const double fact =
      (x[0] - kc * x[std::size_t(n - 1)] / gamma) / (1.0 + z[0] - kc * z[n - 1] / gamma);
  for (int i = 0; i < n; ++i) x[std::size_t(i)] -= fact * z[i];
}

void solveColumns(std::vector<double>& x, const std::vector<double>& K,
                  const std::vector<double>& a, int n, int lanes, std::vector<double>& work) {
  work.resize(std::size_t(n) * std::size_t(lanes));
  double* cp = work.data();
  double* xs = x.data();
  const double* Ks = K.data();
  for (int i = 0; i < n; ++i) {
    const double ai = a[std::size_t(i)];
    double* xi = xs + std::size_t(i) * lanes;
    double* ci = cp + std::size_t(i) * lanes;
    const double* kr = Ks + std::size_t(i) * lanes;
    if (i == 0) {
      for (int l = 0; l < lanes; ++l) {
        const double right = n > 1 ? kr[l] : 0.0;
        const double denom = ai + right;
        ci[l] = -right / denom;
        xi[l] = ai * xi[l] / denom;
      }
      continue;
    }
    const double* kl = Ks + std::size_t(i - 1) * lanes;
    const double* cPrev = cp + std::size_t(i - 1) * lanes;
    const double* xPrev = xs + std::size_t(i - 1) * lanes;
    const bool last = i + 1 == n;
    for (int l = 0; l < lanes; ++l) {
      const double right = last ? 0.0 : kr[l];
      const double denom = (ai + kl[l] + right) + kl[l] * cPrev[l];
      ci[l] = -right / denom;
      xi[l] = (ai * xi[l] + kl[l] * xPrev[l]) / denom;
    }
  }
  for (int i = n - 2; i >= 0; --i) {
    double* xi = xs + std::size_t(i) * lanes;
    const double* xn = xs + std::size_t(i + 1) * lanes;
    const double* ci = cp + std::size_t(i) * lanes;
    for (int l = 0; l < lanes; ++l) xi[l] -= ci[l] * xn[l];
  }
}

void solveChainInPlace(double* __restrict x, const double* __restrict a, const double* __restrict K,
                       int n, double* __restrict cp) {
  double kPrev = 0.0, cPrev = 0.0, yPrev = 0.0;
  for (int i = 0; i < n; ++i) {
    const double kr = i + 1 < n ? K[i] : 0.0;
    const double diag = a[i] + kPrev + kr;
    const double denom = diag + kPrev * cPrev;
    cp[i] = -kr / denom;
    const double y = (a[i] * x[i] + kPrev * yPrev) / denom;
    x[i] = y;
    yPrev = y;
    cPrev = cp[i];
    kPrev = kr;
  }
  for (int i = n - 2; i >= 0; --i) x[i] -= cp[i] * x[i + 1];
}

namespace {

// Thomas algorithm for diag[i] x_i - K[i-1] x_{i-1} - K[i] x_{i+1} = x_i (x holds the right-hand
// side on entry), i < n, the faces K[i] for i < n - 1.
void thomasWeighted(double* x, const double* diag, const double* K, int n, double* cp) {
  double kPrev = 0.0, cPrev = 0.0;
  for (int i = 0; i < n; ++i) {
    const double kr = i + 1 < n ? K[i] : 0.0;
    const double denom = diag[i] + kPrev * cPrev;  // sub-diagonal -kPrev, cPrev = -c'_{i-1}
    cp[i] = -kr / denom;
    x[i] = (x[i] + kPrev * (i > 0 ? x[i - 1] : 0.0)) / denom;
    cPrev = cp[i];
    kPrev = kr;
  }
  for (int i = n - 2; i >= 0; --i) x[i] -= cp[i] * x[i + 1];
}

}  // namespace

void solveLine(std::vector<double>& x, const std::vector<double>& a, const std::vector<double>& K,
               bool cyclic, std::vector<double>& work) {
  const int n = int(x.size());
  if (n < 2) return;
  const int faces = cyclic ? n : n - 1;
  int cut = -1;
  bool any = false;
  for (int i = 0; i < faces; ++i) {
    any |= K[std::size_t(i)] > 0.0;
    if (cut < 0 && !(K[std::size_t(i)] > 0.0)) cut = i;
  }
  if (!any) return;
  work.resize(std::size_t(6 * n));
  double* diag = work.data();
  double* cp = work.data() + n;
  double* y = work.data() + 2 * n;
  double* ka = work.data() + 3 * n;  // the faces in solving order
  double* z = work.data() + 4 * n;
  double* ar = work.data() + 5 * n;
  // The open chain from position s (a face at rest at s - 1 cuts a circle there).
  const int s = cyclic && cut >= 0 ? cut + 1 : 0;
  for (int j = 0; j < n; ++j) {
    const std::size_t i = std::size_t((s + j) % n);
    ar[j] = a[i];
    y[j] = a[i] * x[i];
    ka[j] = j + 1 < n ? K[i] : 0.0;
  }
  for (int j = 0; j < n; ++j) diag[j] = ar[j] + (j > 0 ? ka[j - 1] : 0.0) + ka[j];
  if (!cyclic || cut >= 0) {
    thomasWeighted(y, diag, ka, n, cp);
    for (int j = 0; j < n; ++j) x[std::size_t((s + j) % n)] = y[j];
    return;
  }
  // Every face of the circle active: M = T + u v^T with u = (gamma, 0, .., 0, -kc),
  // v = (1, 0, .., 0, -kc / gamma), gamma = -M_00, T the open chain with the corner faces'
  // terms in its first and last diagonal entries.
  const double kc = K[std::size_t(n - 1)];
  diag[0] += kc;
  diag[n - 1] += kc;
  const double gamma = -diag[0];
  diag[0] -= gamma;
  diag[n - 1] -= kc * kc / gamma;
  for (int j = 0; j < n; ++j) z[j] = 0.0;
  z[0] = gamma;
  z[n - 1] = -kc;
  thomasWeighted(y, diag, ka, n, cp);
  thomasWeighted(z, diag, ka, n, cp);
  const double vy = y[0] - kc / gamma * y[n - 1];
  const double vz = z[0] - kc / gamma * z[n - 1];
  const double f = vy / (1.0 + vz);
  for (int j = 0; j < n; ++j) x[std::size_t(j)] = y[j] - f * z[j];
}

}  // namespace ps::sand::kernels
