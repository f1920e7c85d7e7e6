#pragma once
#include <algorithm>
#include <cmath>
#include <span>
#include <string>

#include "edit/tool.hpp"

namespace ps::edit {

// Paper 003's height function (equation 7), g(x) = exp(-(x - mu)^2 / (2 sigma^2)) / (sigma sqrt(2
// pi)), evaluated on the normalised distance x = 1 - d / r_d, where d is the 3D distance on the
// sphere between the vertex and the control vertex (DistanceField) and r_d the radius of
// deformation: x = 1 at the control vertex, x = 0 on the border of V_d. With the paper's mu = 1 the
// maximum sits at the control vertex and the profile falls towards the border.
//
// The profile used is g shifted and scaled so that it is exactly 0 on the border and 1 at the
// control vertex (the factor 1 / (sigma sqrt(2 pi)) cancels):
//     shape(d) = (g(1 - d/r_d) - g(0)) / (g(1) - g(0)),   0 <= d <= r_d.
// Subtracting g(0) keeps the edit continuous at the border: with sigma = 0.75 the raw Gaussian is
// still 41 % of its peak there and would leave a cliff; with sigma = 0.17 the shift is 3e-8. So
// `strength` is the height change at the control vertex, whatever sigma. Written with y = d / r_d
// in the cancellation-free form
//     shape = (exp(c y (y + 2 mu - 2)) - e0) / (1 - e0),  c = -1 / (2 sigma^2),  e0 = exp(c (2 mu -
//     1)).
// mu must exceed 0.5 (else the border would be at least as high as the centre); for 0.5 < mu < 1
// the peak is a ring inside the area and shape exceeds 1 there.
class GaussianProfile {
 public:
  // Throws core::InputError like BrushSettings::validate for a bad radius, sigma or mu.
  GaussianProfile(double radius, double sigma, double mu);

  double operator()(double d) const {
    const double y = d * invRadius_;
    // q > 0 only inside the ring of a mu < 1 profile; capped so that shape stays finite.
    const double q = std::min(c_ * y * (y + twoMuMinus2_), 700.0);
    const double s = (std::exp(q) - e0_) * invDenominator_;
    return s > 0.0 ? s : 0.0;
  }
  double fromDistance2(double d2) const { return (*this)(std::sqrt(d2)); }

  double radius() const { return radius_; }

 private:
  double radius_, invRadius_, c_, twoMuMinus2_, e0_, invDenominator_;
};

enum class BrushMode {
  kRaise,  // h += a * shape
  kLower,  // h -= a * shape
  kSet,    // h moves toward `target` by at most a * shape
};
std::string toString(BrushMode mode);
BrushMode brushModeFromString(const std::string& s);  // throws core::InputError

struct BrushSettings {
  double radius = 300e3;  // r_d (m), at least 1 mm
  double sigma = 0.17;    // paper 003 used 0.17 and 0.75
  double mu = 1.0;        // paper 003 used 1
  BrushMode mode = BrushMode::kRaise;
  // a, the change at the control vertex: metres per stamp, or metres per second when `rate`
  // (then a = strength * dt of the stamp).
  double strength = 1000.0;
  bool rate = false;
  double target = 0.0;    // kSet: the height to move toward (m)
  double spacing = 0.25;  // stroke stamp spacing as a fraction of r_d, in (0, 1]

  // Throws core::InputError naming the first bad field and its value.
  void validate() const;
  bool operator==(const BrushSettings&) const = default;
};

// The Gaussian brush: the first Tool. Heights are computed in double from the old float height,
// clamped to +-heightLimit and rounded to float. apply() returns the rectangle of the vertices
// whose height actually changed (far out, where a * shape is below half a float step, heights
// stay bitwise the same and need no bounds update). Rows are processed in parallel (OpenMP); on the
// lat-long chart the Gaussian is evaluated once per distinct (row, folded column distance), so a
// row costs about half its length in exp() calls and a row at constant distance (any row when
// the control vertex is a pole) one call.
class GaussianBrush final : public Tool {
 public:
  explicit GaussianBrush(BrushSettings settings = {}) : settings_(settings) {}

  const BrushSettings& settings() const { return settings_; }
  void setSettings(const BrushSettings& s) { settings_ = s; }

  std::string name() const override { return "gaussian"; }
  void validate() const override { settings_.validate(); }
  double radius() const override { return settings_.radius; }
  double spacing() const override { return settings_.spacing * settings_.radius; }
  bool rateBased() const override { return settings_.rate; }
  terrain::VertexBox apply(const ToolContext& ctx, std::span<float> heights) const override;

 private:
  BrushSettings settings_;
};

// The largest float <= limit (a clamp target that survives rounding to float).
float floatAtMost(double limit);

}  // namespace ps::edit
