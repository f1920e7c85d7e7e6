#include "edit/brush.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "core/input_error.hpp"
#include "core/named_values.hpp"

namespace ps::edit {

namespace {

void checkRadius(double r) {
  if (!std::isfinite(r) || !(r > 0.0)) {
    throw core::InputError("radius of deformation r_d = " + core::exactNumber(r) +
                           " m must be finite and > 0");
  }
  if (r < 1e-3) {
    throw core::InputError("radius of deformation r_d = " + core::exactNumber(r) +
                           " m is below the smallest usable 1 mm");
  }
}
void checkSigma(double sigma) {
  if (!std::isfinite(sigma) || !(sigma > 0.0)) {
    throw core::InputError("sigma = " + core::exactNumber(sigma) + " must be finite and > 0");
  }
  if (sigma < 1e-6 || sigma > 1e6) {
    throw core::InputError("sigma = " + core::exactNumber(sigma) +
                           " is outside the usable range [1e-6, 1e6]");
  }
}
void checkMu(double mu) {
  if (!std::isfinite(mu) || !(mu > 0.5) || mu > 1e6) {
    throw core::InputError(
        "mu = " + core::exactNumber(mu) +
        " must be in (0.5, 1e6]: the Gaussian must be higher at the control vertex "
        "(x = 1) than on the border (x = 0)");
  }
}

}  // namespace

GaussianProfile::GaussianProfile(double radius, double sigma, double mu) {
  checkRadius(radius);
  checkSigma(sigma);
  checkMu(mu);
  radius_ = radius;
  invRadius_ = 1.0 / radius;
  c_ = -1.0 / (2.0 * sigma * sigma);
  twoMuMinus2_ = 2.0 * mu - 2.0;
  const double q0 = c_ * (2.0 * mu - 1.0);  // < 0
  e0_ = std::exp(q0);
  invDenominator_ = -1.0 / std::expm1(q0);
}

namespace {
constexpr core::NameTable<BrushMode, 3> kBrushModes{
    "brush mode",
    {{{BrushMode::kRaise, "raise"}, {BrushMode::kLower, "lower"}, {BrushMode::kSet, "set"}}}};
}  // namespace

std::string toString(BrushMode mode) {
  return kBrushModes.nameOf(mode);
}

BrushMode brushModeFromString(const std::string& s) {
  return kBrushModes.parse(s);
}

void BrushSettings::validate() const {
  checkRadius(radius);
  checkSigma(sigma);
  checkMu(mu);
  if (!std::isfinite(strength) || strength < 0.0) {
    throw core::InputError("strength = " + core::exactNumber(strength) + (rate ? " m/s" : " m") +
                           " must be finite and >= 0");
  }
  if (!std::isfinite(target))
    throw core::InputError("target = " + core::exactNumber(target) + " m must be finite");
  if (!std::isfinite(spacing) || !(spacing > 0.0) || spacing > 1.0) {
    throw core::InputError("spacing = " + core::exactNumber(spacing) +
                           " (a fraction of r_d) must be in (0, 1]");
  }
  if (mode != BrushMode::kRaise && mode != BrushMode::kLower && mode != BrushMode::kSet) {
    throw core::InputError("brush mode " + std::to_string(int(mode)) +
                           " is not raise, lower or set");
  }
}

float floatAtMost(double limit) {
  float f = static_cast<float>(limit);
  if (double(f) > limit) f = std::nextafter(f, -INFINITY);
  return f;
}

namespace {

// New height from the old one and the brush weight w = a * shape >= 0.
struct Raise {
  double operator()(float h, double w) const { return double(h) + w; }
};
struct Lower {
  double operator()(float h, double w) const { return double(h) - w; }
};
struct SetToward {
  double target;
  double operator()(float h, double w) const {
    return double(h) + std::clamp(target - double(h), -w, w);
  }
};

// The seam-wrapped rectangle of the columns within folded distance k of column uc, rows v0..v1.
terrain::VertexBox symmetricBounds(int uc, int k, int v0, int v1, int m) {
  terrain::VertexBox r{0, m, v0, v1};
  if (2 * k + 1 >= m) return r;
  r.uBegin = uc - k;
  r.uEnd = uc + k;
  if (r.uEnd >= m) r.uBegin -= m, r.uEnd -= m;  // wrap through u = m / 0: both twins included
  if (r.uBegin == 0) {                          // column 0 without wrapping: name u = m as well
    if (r.uEnd == 0) {
      r.uBegin = -1;  // {0, m} alone has no VertexBox: take m - 1 too
    } else {
      r.uBegin = m, r.uEnd += m;  // u = m, then 0 .. uEnd
    }
  }
  return r;
}

// Writes the new heights of V_d and returns the rectangle of the vertices that actually changed
// (bitwise): far out, where the Gaussian is below half a float step, heights stay as they were
// and the bounds above them need no update.
template <class Op>
terrain::VertexBox applyRows(const ToolContext& ctx, const GaussianProfile& profile, double amount,
                             const Op& op, std::span<float> heights) {
  const Region& region = ctx.region;
  const DistanceField& field = ctx.field;
  const core::GridSize g = field.grid();
  const std::size_t side = std::size_t(g.side());
  const double limit = ctx.heightLimit;
  float* const h = heights.data();
  auto store = [limit](float& x, double y) {  // true when the stored height changed
    const float old = x;
    x = static_cast<float>(std::clamp(y, -limit, limit));
    return std::bit_cast<std::uint32_t>(x) != std::bit_cast<std::uint32_t>(old);
  };
  const int v0 = region.vBegin(), v1 = region.vEnd();
  const bool parallel = region.vertexCount() > 8192;
  // Per row: the largest folded column distance of a changed vertex (symmetric regions), or
  // 0 when anything changed (other regions); -1 when nothing did.
  std::vector<int> reach(std::size_t(v1 - v0 + 1), -1);

  // Small regions stay on this thread without entering the OpenMP runtime: a region with
  // if (false) still sets up a team of one and wakes the pool's sleeping threads.
  if (field.latLong() && region.symmetric()) {
    // weight: per folded column distance k, reused from row to row by one thread.
    auto applyRow = [&](int v, std::vector<double>& weight) {
      const auto spans = region.row(v);
      if (spans.empty()) return;
      float* row = h + std::size_t(v) * side;
      const DistanceField::Row terms = field.row(v);
      int kChanged = -1;
      if (terms.f == 0.0) {  // every vertex of the row at one distance (pole rows, polar centre)
        const double w = amount * profile.fromDistance2(field.distance2(terms, 0));
        for (const Span& s : spans) {
          for (int u = s.uBegin; u <= s.uEnd; ++u) {
            if (store(row[u], op(row[u], w))) kChanged = std::max(kChanged, field.fold(u));
          }
        }
      } else {
        const int kMax = region.halfWidth(v);
        weight.resize(std::size_t(kMax) + 1);
        for (int k = 0; k <= kMax; ++k) {
          weight[std::size_t(k)] = amount * profile.fromDistance2(field.distance2(terms, k));
        }
        for (const Span& s : spans) {
          for (int u = s.uBegin; u <= s.uEnd; ++u) {
            const int k = field.fold(u);
            if (store(row[u], op(row[u], weight[std::size_t(k)]))) kChanged = std::max(kChanged, k);
          }
        }
      }
      reach[std::size_t(v - v0)] = kChanged;
    };
    if (parallel) {
#pragma omp parallel
      {
        std::vector<double> weight;
#pragma omp for schedule(dynamic, 2)
        for (int v = v0; v <= v1; ++v) applyRow(v, weight);
      }
    } else {
      std::vector<double> weight;
      for (int v = v0; v <= v1; ++v) applyRow(v, weight);
    }
  } else {
    // Any chart: one distance per vertex, a span's at once: region growing's where it kept
    // them (the same bits), else from the chart's row positions.
    auto applyRow = [&](int v) {
      thread_local std::vector<double> d2;
      float* row = h + std::size_t(v) * side;
      bool changed = false;
      for (const Span& s : region.row(v)) {
        d2.resize(std::size_t(s.size()));
        if (!ctx.distances || !ctx.distances->copy(v, s.uBegin, s.uEnd, d2.data()))
          field.rowDistances2(v, s.uBegin, s.uEnd, d2.data());
        for (int u = s.uBegin; u <= s.uEnd; ++u) {
          const double w = amount * profile.fromDistance2(d2[std::size_t(u - s.uBegin)]);
          changed |= store(row[u], op(row[u], w));
        }
      }
      reach[std::size_t(v - v0)] = changed ? 0 : -1;
    };
    // Only the rows holding vertices: a region across a fold is two or four bands of rows far
    // apart (the octahedral chart's south pole: rows near 0 and near m), and handing the empty
    // rows between them to the team, two at a time, took a third of the Gaussian's time there.
    std::vector<int> rows;
    for (int v = v0; v <= v1; ++v)
      if (!region.row(v).empty()) rows.push_back(v);
    const int count = int(rows.size());
    if (parallel) {
#pragma omp parallel for schedule(dynamic, 2)
      for (int i = 0; i < count; ++i) applyRow(rows[std::size_t(i)]);
    } else {
      for (int v : rows) applyRow(v);
    }
  }
  int first = -1, last = -1, kMax = -1;
  for (int v = v0; v <= v1; ++v) {
    const int k = reach[std::size_t(v - v0)];
    if (k < 0) continue;
    if (first < 0) first = v;
    last = v;
    kMax = std::max(kMax, k);
  }
  if (first < 0) return terrain::VertexBox::none();
  if (field.latLong() && region.symmetric()) {
    return symmetricBounds(region.centreU(), kMax, first, last, g.m());
  }
  // The rows that changed, within the region's box. On a chart whose dirty box is a part of the
  // region that the box's images across the glued sides complete (the octahedral chart's
  // quadrant, the torus's half: core::Chart::gluedImages), the region is symmetric and so is the
  // box; whether a float changed is not (a small amount rounds away on a large height and not
  // on a small one), so the box is kept whole there (found by StressEdits.RandomBrushActions
  // OnTheOctahedralChartKeepEveryInvariant).
  terrain::VertexBox r = region.bounds();
  if (!ctx.terrain.chart().gluesSidesBeyondSeam() &&
      std::max(r.vBegin, first) <= std::min(r.vEnd, last)) {
    r.vBegin = std::max(r.vBegin, first);
    r.vEnd = std::min(r.vEnd, last);
  }
  return r;
}

}  // namespace

terrain::VertexBox GaussianBrush::apply(const ToolContext& ctx, std::span<float> heights) const {
  settings_.validate();
  const GaussianProfile profile(settings_.radius, settings_.sigma, settings_.mu);
  // Capped so that amount * shape can overflow to inf (which clamps) but never be inf * 0 = NaN.
  const double amount =
      std::min(settings_.rate ? settings_.strength * ctx.input.dt : settings_.strength,
               std::numeric_limits<double>::max());
  if (ctx.region.empty()) return terrain::VertexBox::none();
  switch (settings_.mode) {
    case BrushMode::kRaise:
      return applyRows(ctx, profile, amount, Raise{}, heights);
    case BrushMode::kLower:
      return applyRows(ctx, profile, amount, Lower{}, heights);
    case BrushMode::kSet:
      return applyRows(ctx, profile, amount, SetToward{settings_.target}, heights);
  }
  return ctx.region.bounds();
}

}  // namespace ps::edit
