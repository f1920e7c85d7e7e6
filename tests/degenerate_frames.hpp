#pragma once
// The degenerate frames the tracking stress tests (test_stress_tracking.cpp) feed to the
// detectors, the scene tracker and the FrameStepper: rendered views of the short scene's camera
// with the markers edge-on, tiny, blurred, occluded, in noise, darkness or saturation; markers
// pasted over each other; blank, noise-only, 1x1 and odd-sized frames; frames of types the
// detectors refuse. Seeded and deterministic, made once per test process (cases()).
#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <string>
#include <utility>
#include <vector>

#include "tracking/synth.hpp"

namespace ps::stresstest {

inline constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
inline constexpr double kInf = std::numeric_limits<double>::infinity();
inline const cv::Size kSize{320, 240};

// A frame to stress with. `toolPossible` is false for frames in which no marker can be seen at
// all (blank, noise, a few pixels, refused types): there the tracker may only hold its last
// pose, then lose it, and a fresh stepper must never edit.
struct Case {
  std::string name;
  cv::Mat image;
  bool toolPossible = true;
  bool refused = false;  // the image type is not 8-bit grey/BGR/BGRA: InputError expected
};

// The short scene's camera (0.4 m away, 55 degrees up) with the tool hovering 10 mm above the
// planet at 55 N 120 W, where both back ends find both markers in the whole frame (so a correct
// track never touches).
inline tracking::SynthKey hoverKey() {
  tracking::SynthKey k;
  k.camDistance = 0.4;
  k.camElevationDeg = 55;
  k.camAzimuthDeg = -90;
  k.tipLatDeg = 55;
  k.tipLonDeg = -120;
  k.tipHeightMm = 10;
  k.toolTiltDeg = 15;
  k.toolTurnDeg = 0;
  k.blur = 0.3;
  k.noise = 1.0;
  k.gain = 1.0;
  return k;
}

inline tracking::SynthScript scriptFor(std::vector<tracking::SynthKey> keys,
                                       cv::Size size = kSize) {
  auto s = tracking::builtinScene("short");
  s.colour = false;
  s.size = size;
  s.camera = tracking::SynthScript::syntheticCamera(size);
  for (std::size_t i = 0; i < keys.size(); ++i) keys[i].frame = double(i);
  s.keys = std::move(keys);
  return s;
}

// Rendered degenerate views: each key is rendered exactly (keys at consecutive frames).
inline std::vector<Case> renderedCases() {
  std::vector<std::pair<std::string, tracking::SynthKey>> keys;
  const auto add = [&](const std::string& name, const std::function<void(tracking::SynthKey&)>& f) {
    tracking::SynthKey k = hoverKey();
    f(k);
    keys.emplace_back(name, k);
  };
  add("good", [](auto&) {});
  // The tool marker turned away from the camera up to edge-on.
  for (double turn : {60.0, 75.0, 82.0, 86.0, 88.0, 89.0, -89.0})
    add("tool turned " + std::to_string(int(turn)) + " deg",
        [&](auto& k) { k.toolTurnDeg = turn; });
  // The planet marker (on the table) seen at grazing elevation: up to about 89 degrees of tilt.
  for (double elev : {12.0, 6.0, 3.0, 1.0})
    add("camera elevation " + std::to_string(int(elev)) + " deg",
        [&](auto& k) { k.camElevationDeg = elev; });
  // Tiny: a 5 cm tool marker at fx = 300 px is 5 px wide at 3 m, 1.5 px at 10 m.
  for (double d : {1.5, 3.0, 6.0, 10.0})
    add("camera at " + std::to_string(d) + " m", [&](auto& k) { k.camDistance = d; });
  // Heavy defocus.
  for (double b : {3.0, 6.0, 12.0, 19.9})
    add("blur " + std::to_string(int(b)) + " px", [&](auto& k) { k.blur = b; });
  // A hand over the planet marker: half of it and more.
  for (double o : {0.35, 0.5, 0.8, 2.0})
    add("occlusion " + std::to_string(o), [&](auto& k) { k.occlusion = o; });
  // Sensor noise, darkness and saturation.
  for (double n : {25.0, 45.0, 63.0})
    add("noise " + std::to_string(int(n)), [&](auto& k) { k.noise = n; });
  add("gain 0.02", [](auto& k) { k.gain = 0.02; });
  add("gain 3.99", [](auto& k) { k.gain = 3.99; });
  add("tiny, blurred and noisy", [](auto& k) {
    k.camDistance = 2.5;
    k.blur = 2.0;
    k.noise = 30;
  });
  add("edge-on and blurred", [](auto& k) {
    k.toolTurnDeg = 85;
    k.camElevationDeg = 4;
    k.blur = 4;
  });
  std::vector<tracking::SynthKey> only;
  for (const auto& [name, k] : keys) only.push_back(k);
  const tracking::SynthRenderer r(scriptFor(only));
  std::vector<Case> out;
  for (std::size_t i = 0; i < keys.size(); ++i) out.push_back({keys[i].first, r.render(int(i))});
  return out;
}

inline cv::Rect boundsOf(const std::array<cv::Point2d, 4>& c, double margin, cv::Size frame) {
  double x0 = 1e18, y0 = 1e18, x1 = -1e18, y1 = -1e18;
  for (const auto& p : c) {
    x0 = std::min(x0, p.x), x1 = std::max(x1, p.x);
    y0 = std::min(y0, p.y), y1 = std::max(y1, p.y);
  }
  const double m = margin * std::max(x1 - x0, y1 - y0);
  return cv::Rect(cv::Point(int(std::floor(x0 - m)), int(std::floor(y0 - m))),
                  cv::Point(int(std::ceil(x1 + m)), int(std::ceil(y1 + m)))) &
         cv::Rect({0, 0}, frame);
}

// Pastes `src(from)` into `dst` at `at` (clipped to the frame).
inline void paste(const cv::Mat& src, cv::Rect from, cv::Mat& dst, cv::Point at) {
  cv::Rect to(at, from.size());
  const cv::Rect clipped = to & cv::Rect({0, 0}, dst.size());
  from = cv::Rect(from.tl() + (clipped.tl() - to.tl()), clipped.size());
  if (clipped.area() > 0) src(from).copyTo(dst(clipped));
}

// Two markers overlapping: copies of the planet marker (and the tool marker) pasted over each
// other in the good frame.
inline std::vector<Case> overlapCases(const cv::Mat& good) {
  const auto script = scriptFor({hoverKey()});
  const tracking::SynthRenderer r(script);
  const auto truth = r.truth(0);
  const auto planet = boundsOf(
      tracking::projectMarker(truth.planet, script.planetMarkerSize, script.camera), 0.15, kSize);
  const auto tool = boundsOf(
      tracking::projectMarker(truth.tool, script.toolMarkerSize, script.camera), 0.15, kSize);
  std::vector<Case> out;
  cv::Mat a = good.clone();
  paste(good, planet, a, planet.tl() + cv::Point(planet.width / 2, planet.height / 3));
  out.push_back({"planet marker over itself, half shifted", a});
  cv::Mat b = good.clone();
  paste(good, planet, b, planet.tl() + cv::Point(planet.width + 2, 0));
  paste(good, planet, b, planet.tl() - cv::Point(planet.width + 2, 0));
  out.push_back({"planet marker three times side by side", b});
  cv::Mat c = good.clone();
  paste(good, tool, c, planet.tl() + cv::Point(planet.width / 4, planet.height / 4));
  out.push_back({"tool marker over the planet marker", c});
  cv::Mat d = good.clone();
  paste(good, tool, d, tool.tl() + cv::Point(tool.width / 3, tool.height / 5));
  out.push_back({"tool marker over itself, a third shifted", d});
  return out;
}

inline std::vector<Case> syntheticCases(const cv::Mat& good) {
  std::vector<Case> out;
  out.push_back({"all black", cv::Mat(kSize, CV_8U, cv::Scalar(0)), false});
  out.push_back({"all white", cv::Mat(kSize, CV_8U, cv::Scalar(255)), false});
  out.push_back({"mid grey", cv::Mat(kSize, CV_8U, cv::Scalar(128)), false});
  cv::RNG rng(20260901);
  cv::Mat uniform(kSize, CV_8U);
  rng.fill(uniform, cv::RNG::UNIFORM, 0, 256);
  out.push_back({"uniform noise", uniform, false});
  cv::Mat gauss(kSize, CV_8U);
  rng.fill(gauss, cv::RNG::NORMAL, 128, 70);
  out.push_back({"gaussian noise", gauss, false});
  cv::Mat salt(kSize, CV_8U);
  rng.fill(salt, cv::RNG::UNIFORM, 0, 2);
  salt *= 255;
  out.push_back({"salt and pepper", salt, false});
  cv::Mat blocks;  // blocky noise: many quads, none a marker
  cv::Mat small(kSize.height / 8, kSize.width / 8, CV_8U);
  rng.fill(small, cv::RNG::UNIFORM, 0, 2);
  cv::resize(small * 255, blocks, kSize, 0, 0, cv::INTER_NEAREST);
  out.push_back({"blocky binary noise", blocks, false});
  cv::Mat checker(kSize, CV_8U);
  for (int y = 0; y < checker.rows; ++y)
    for (int x = 0; x < checker.cols; ++x) checker.at<uchar>(y, x) = ((x / 6 + y / 6) % 2) * 255;
  out.push_back({"checkerboard", checker, false});
  // Sizes: a pixel, slivers, odd sizes, a non-continuous view.
  for (cv::Size s : {cv::Size(1, 1), cv::Size(2, 1), cv::Size(1, 2), cv::Size(2, 2), cv::Size(3, 5),
                     cv::Size(7, 7), cv::Size(16, 16), cv::Size(17, 13), cv::Size(1, 240),
                     cv::Size(320, 1), cv::Size(33, 31)}) {
    cv::Mat m;
    cv::resize(good, m, s, 0, 0, cv::INTER_AREA);
    out.push_back({std::to_string(s.width) + "x" + std::to_string(s.height), m, false});
  }
  out.push_back({"319x239 view (not continuous)", good(cv::Rect(1, 1, 319, 239)), true});
  cv::Mat half;
  cv::resize(good, half, {161, 121}, 0, 0, cv::INTER_AREA);
  out.push_back({"161x121", half, true});
  cv::Mat odd = cv::Mat(241, 323, CV_8U, cv::Scalar(90));
  good.copyTo(odd(cv::Rect(1, 0, 320, 240)));
  out.push_back({"323x241 frame, the image inside", odd, true});
  // Types: colour is converted; anything not 8-bit, or 2 channels, is refused.
  cv::Mat bgr, bgra;
  cv::cvtColor(good, bgr, cv::COLOR_GRAY2BGR);
  cv::cvtColor(good, bgra, cv::COLOR_GRAY2BGRA);
  out.push_back({"8-bit BGR", bgr, true});
  out.push_back({"8-bit BGRA", bgra, true});
  const auto refused = [&](const std::string& name, const cv::Mat& m) {
    out.push_back({name, m, false, true});
  };
  cv::Mat f32, f64, u16, s8, f32c3;
  good.convertTo(f32, CV_32F, 1.0 / 255);
  good.convertTo(f64, CV_64F);
  good.convertTo(u16, CV_16U, 257);
  good.convertTo(s8, CV_8S, 0.5);
  bgr.convertTo(f32c3, CV_32FC3);
  refused("CV_32F", f32);
  refused("CV_64F", f64);
  refused("CV_16U", u16);
  refused("CV_8S", s8);
  refused("CV_32FC3", f32c3);
  cv::Mat f32nan = f32.clone();
  f32nan.setTo(cv::Scalar(kNaN));
  refused("CV_32F all NaN", f32nan);
  cv::Mat two;
  cv::merge(std::vector<cv::Mat>{good, good}, two);
  refused("8-bit, 2 channels", two);
  cv::Mat five;
  cv::merge(std::vector<cv::Mat>{good, good, good, good, good}, five);
  refused("8-bit, 5 channels", five);
  refused("empty", cv::Mat());
  return out;
}

inline std::vector<Case> allCases() {
  auto cases = renderedCases();
  const cv::Mat good = cases.front().image;
  for (auto& c : overlapCases(good)) cases.push_back(std::move(c));
  for (auto& c : syntheticCases(good)) cases.push_back(std::move(c));
  return cases;
}

inline const std::vector<Case>& cases() {
  static const std::vector<Case> c = allCases();
  return c;
}

}  // namespace ps::stresstest
