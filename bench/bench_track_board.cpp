// `planetsculpt bench track`, the planet board and tool cube rows (issue 24): the synthetic board
// scenes (tracking/synth.hpp: board-sweep, board-hand, board-hidden, cube-spin, board-demo)
// replayed through the frame stepper that `replay` and `live` run, against their ground truth:
//   * the planet has a pose in frames where at least one board marker is at least half visible
//     (target >= 99 %), and in frames where the board is fully hidden and the camera stands
//     where it was when the board was last seen (>= 95 %); false holds (the camera moved, the
//     planet held more than 5 mm off) and false losses (hidden, camera still, no pose);
//   * the planet centre's error (median <= 1 mm, p95 <= 3 mm);
//   * the tool tip's error and flips while the cube turns; touching frames sculpted;
//   * detection + tracking time per frame (one thread), against the single-marker default
//     detector's on the sweep measured in the same run (target <= 1.5x).
#include <cmath>
#include <nlohmann/json.hpp>
#include <opencv2/core/utility.hpp>

#include "app/build_paths.hpp"
#include "app/progress.hpp"
#include "bench/bench_track_board.hpp"
#include "bench/bench_util.hpp"
#include "core/latlong_chart.hpp"
#include "edit/control_vertex.hpp"
#include "replay/replay.hpp"
#include "terrain/relief.hpp"
#include "tracking/synth.hpp"

namespace ps::bench {

namespace {

constexpr double kTouch = 0.004;  // m, the replay's default touch distance

double r3(double v) {
  return std::isfinite(v) ? std::round(v * 1000) / 1000 : -1;
}

double fraction(int part, int whole) {
  return whole > 0 ? double(part) / whole : 1.0;
}

void evaluateScene(const std::string& scene, bool quick, double singleMarkerMs, std::ostream& out) {
  const tracking::SynthScript script = tracking::builtinScene(scene, app::sourceDir());
  const tracking::SynthRenderer renderer(script);
  // A small planet: the stepper's edits are not what is timed here.
  const auto chart = std::make_shared<core::LatLongChart>(core::GridSize::fromSide(129), 1.0e6);
  terrain::Terrain planet(chart, std::vector<float>(chart->grid().count(), 0.0f));
  replay::ReplayOptions o;
  o.scene.useBoard(script.board);
  o.scene.useToolLayout(script.toolLayout);
  o.scene.planetRadius = script.planetRadius;
  o.scene.touchDistance = kTouch;
  replay::FrameStepper stepper(script.camera, planet, o);
  const core::LatLongChart cvChart(core::GridSize::fromSide(2049), 1.0);

  int halfVisible = 0, halfVisibleWithPose = 0, hiddenStill = 0, hiddenStillWithPose = 0;
  int hiddenMoved = 0, falseHolds = 0, heldMoved = 0, toolVisible = 0, toolWithTip = 0, flips = 0;
  int touching = 0, sculpted = 0, cvWithin = 0;
  std::vector<double> centreErr, tipErr, ms, detectMs, trackMs;
  tracking::Pose lastSeenCamera;
  bool seen = false;
  const int frames = quick ? std::min(renderer.frames(), 120) : renderer.frames();
  app::Progress progress("track " + scene);
  for (int f = 0; f < frames; ++f) {
    const auto truth = renderer.truth(f);
    const auto step = stepper.step(renderer.render(f), f, truth.time);
    ms.push_back(step.times.detectMs + step.times.trackMs);
    detectMs.push_back(step.times.detectMs);
    trackMs.push_back(step.times.trackMs);
    const auto& sf = step.scene;
    const double err = sf.planetCentreValid
                           ? (sf.planetCentreCamera - truth.planetCentreCamera).norm()
                           : std::numeric_limits<double>::infinity();
    if (truth.boardHalfVisible > 0) {
      ++halfVisible;
      halfVisibleWithPose += sf.planetCentreValid;
      if (sf.planetCentreValid) centreErr.push_back(1e3 * err);
    } else if (seen) {
      const bool asWhenSeen = tracking::rotationAngle(lastSeenCamera.R, truth.camera.R) < 1e-6 &&
                              (lastSeenCamera.t - truth.camera.t).norm() < 1e-6;
      if (asWhenSeen) {
        ++hiddenStill;
        hiddenStillWithPose += sf.planetCentreValid;
      } else {
        ++hiddenMoved;
        heldMoved += sf.planetCentreValid;
        falseHolds += sf.planetCentreValid && err > 5e-3;
      }
    }
    if (sf.planet.measured) {
      lastSeenCamera = truth.camera;
      seen = true;
    }
    if (truth.toolVisible && sf.planetCentreValid) {
      ++toolVisible;
      if (sf.tipValid) {
        ++toolWithTip;
        tipErr.push_back(1e3 * (sf.tipPlanet - truth.tipPlanet).norm());
        flips += tracking::rotationAngle(sf.tool.pose.R, truth.tool.R) > 15 * M_PI / 180;
      }
    }
    if (truth.tipHeight <= kTouch && truth.toolVisible) {
      ++touching;
      sculpted += step.touching;
      if (step.touching) {
        const auto a = edit::nearestVertex(cvChart, sf.tipPlanet);
        const auto b = edit::nearestVertex(cvChart, truth.tipPlanet);
        cvWithin += (cvChart.position(a.u, a.v, 0) - cvChart.position(b.u, b.v, 0)).norm() *
                        script.planetRadius <=
                    0.003;
      }
    }
    progress.update(double(f + 1) / frames);
  }
  progress.done(std::to_string(frames) + " frames");
  nlohmann::json j = {
      {"bench", "track"},
      {"scene", scene},
      {"detector", "apriltag d2 + regions"},
      {"markers", "board + cube"},
      {"resolution", std::to_string(script.size.width) + "x" + std::to_string(script.size.height)},
      {"frames", frames},
      {"ms", r3(median(ms))},
      {"ms_p95", r3(percentile(ms, 0.95))},
      {"detect_ms", r3(median(detectMs))},
      {"track_ms", r3(median(trackMs))},
      {"half_visible_frames", halfVisible},
      {"pose_when_half_visible", r3(fraction(halfVisibleWithPose, halfVisible))},
      {"hidden_still_frames", hiddenStill},
      {"pose_when_hidden_still", r3(fraction(hiddenStillWithPose, hiddenStill))},
      {"false_losses", hiddenStill - hiddenStillWithPose},
      {"hidden_moved_frames", hiddenMoved},
      {"held_after_camera_moved", heldMoved},
      {"false_holds", falseHolds},
      {"planet_centre_error_median_mm", r3(median(centreErr))},
      {"planet_centre_error_p95_mm", r3(percentile(centreErr, 0.95))},
      {"tool_visible_frames", toolVisible},
      {"tip_when_tool_visible", r3(fraction(toolWithTip, toolVisible))},
      {"tip_error_median_mm", r3(median(tipErr))},
      {"tip_error_p95_mm", r3(percentile(tipErr, 0.95))},
      {"flips", flips},
      {"touching_frames", touching},
      {"sculpted_when_touching", r3(fraction(sculpted, touching))},
      {"control_vertex_within_3mm", r3(fraction(cvWithin, sculpted))}};
  if (singleMarkerMs > 0) j["ms_over_single_marker_default"] = r3(median(ms) / singleMarkerMs);
  out << j.dump() << std::endl;
}

}  // namespace

void benchTrackBoards(const BenchOptions& o, double singleMarkerMs, std::ostream& out) {
  for (const char* scene : {"board-sweep", "board-hand", "board-hidden", "cube-spin", "board-demo"})
    if (!o.quick || std::string(scene) != "board-demo")
      evaluateScene(scene, o.quick, singleMarkerMs, out);
}

}  // namespace ps::bench
