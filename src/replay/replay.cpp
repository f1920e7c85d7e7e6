#include "replay/replay.hpp"

#include <chrono>
#include <cmath>
#include <nlohmann/json.hpp>

#include "core/input_error.hpp"
#include "edit/control_vertex.hpp"
#include "edit/edit_pipeline.hpp"

namespace ps::replay {

namespace {

double round6(double v) {
  return std::round(v * 1e6) / 1e6;
}
nlohmann::json vec(const Eigen::Vector3d& v) {
  return {round6(v.x()), round6(v.y()), round6(v.z())};
}

nlohmann::json markerJson(const tracking::MarkerEstimate& m) {
  nlohmann::json j = {{"state", tracking::toString(m.state)}};
  if (m.usable()) {
    j["rvec"] = vec(m.pose.rvec());
    j["tvec"] = vec(m.pose.t);
  }
  if (m.measured) {
    j["reprojection_px"] = std::round(m.rms * 1000) / 1000;
    if (std::isfinite(m.ratio)) j["ambiguity_ratio"] = std::round(m.ratio * 100) / 100;
    if (m.byContinuity) j["by_continuity"] = true;
  }
  return j;
}

double msSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

std::string toString(ReplayTool t) {
  return t == ReplayTool::kBrush ? "brush" : "displace";
}

ReplayTool replayToolFromString(const std::string& s) {
  if (s == "brush") return ReplayTool::kBrush;
  if (s == "displace") return ReplayTool::kDisplace;
  throw core::InputError("unknown replay tool '" + s + "' (brush or displace)");
}

sand::DisplacementSettings ReplayOptions::defaultDisplacement() {
  sand::DisplacementSettings d;
  d.radius = 400e3;
  d.rampartWidth = 0.5;
  return d;
}

edit::BrushSettings ReplayOptions::defaultBrush() {
  edit::BrushSettings b;
  b.radius = 250e3;
  b.strength = 600.0;
  return b;
}

void ReplayOptions::validate() const {
  detector.validate();
  scene.validate();
  brush.validate();
  displace.validate();
  settling.validate();
  if (!(std::isfinite(pressDepth) && pressDepth > 0 && pressDepth <= 2 * displace.radius))
    throw core::InputError("press depth = " + std::to_string(pressDepth) +
                           " m is not in (0, 2 x displacement radius]");
  if (!(fallbackFps > 0 && fallbackFps <= 1000))
    throw core::InputError("fps = " + std::to_string(fallbackFps) + " is not in (0, 1000]");
  if (maxFrames < 0)
    throw core::InputError("max frames = " + std::to_string(maxFrames) + " is negative");
}

ReplaySummary runReplay(tracking::FrameSource& source, const tracking::CameraCalibration& calibIn,
                        terrain::Terrain& planet, const ReplayOptions& o, std::ostream& log,
                        std::ostream* timings, const ProgressFn& progress, const FrameHook& hook) {
  o.validate();
  const tracking::CameraCalibration calib = calibIn.forImageSize(source.size());
  tracking::DetectorConfig dc = o.detector;
  dc.ids = {o.scene.planet.id, o.scene.tool.id};
  auto detector = tracking::makeDetector(dc);
  tracking::SceneTracker scene(o.scene);
  const core::Chart& chart = planet.chart();
  const double R = chart.radius();
  if (!(R > 0)) throw core::InputError("replay needs a spherical planet (its chart has no radius)");
  const double scale = R / o.scene.planetRadius;  // planet metres per metre of the marker world
  scene.setSurface([&](const Eigen::Vector3d& p) {
    if (!(p.norm() > 0)) return o.scene.planetRadius;
    const auto c = edit::nearestVertex(chart, p);
    return (R + planet.height(c.u, c.v)) / scale;
  });
  edit::EditPipeline pipeline(planet);
  pipeline.setUndoEnabled(o.undo);
  const edit::GaussianBrush brush(o.brush);
  std::optional<sand::Settler> settler;
  if (o.tool == ReplayTool::kDisplace && o.settle)
    settler.emplace(planet, o.displace.material, o.settling);
  const sand::DisplacementTool displacer(planet.chartPtr(), o.displace,
                                         settler ? &*settler : nullptr);
  if (o.tool == ReplayTool::kDisplace) displacer.validate();
  const edit::Tool& tool =
      o.tool == ReplayTool::kBrush ? static_cast<const edit::Tool&>(brush) : displacer;
  // Where the tool acts for a tip over planet point p: the brush at p itself; the displacement
  // sphere at a fixed altitude for the whole stroke (a plough), set when the stroke begins so
  // that its lowest point is pressDepth below the surface at that control vertex. (Setting it
  // from the surface under each stamp would dig deeper with every overlapping stamp.)
  double strokeAltitude = 0;
  auto toolPosition = [&](const Eigen::Vector3d& p, const core::GridPoint& c,
                          bool begin) -> Eigen::Vector3d {
    if (o.tool == ReplayTool::kBrush) return p;
    if (begin) strokeAltitude = R + planet.height(c.u, c.v) - o.pressDepth + o.displace.radius;
    return p.normalized() * strokeAltitude;
  };
  const double fps = source.fps() > 0 ? source.fps() : o.fallbackFps;

  ReplaySummary s;
  s.announcedFrames = source.announcedFrames();
  double lastTime = 0;
  bool anyMarker = false;
  cv::Mat image;
  while ((o.maxFrames == 0 || s.frames < o.maxFrames) && source.read(image)) {
    const int frame = source.index();
    const double time = frame / fps;
    const auto t0 = std::chrono::steady_clock::now();
    nlohmann::json j = {{"frame", frame}, {"time", std::round(time * 1e6) / 1e6}};
    std::vector<tracking::Detection> found;
    double detectMs = 0, trackMs = 0, editMs = 0;
    try {
      found = detector->detect(image);
    } catch (const std::exception& e) {
      j["notes"].push_back(std::string("detection failed: ") + e.what());
    }
    detectMs = msSince(t0);
    const auto t1 = std::chrono::steady_clock::now();
    const auto f = scene.update(found, calib, frame, time);
    trackMs = msSince(t1);
    anyMarker = anyMarker || !found.empty();
    s.framesWithPlanet += f.planet.usable();
    s.framesWithTool += f.tool.usable();
    j["markers"] = found.size();
    j["planet"] = markerJson(f.planet);
    j["tool"] = markerJson(f.tool);
    for (const auto& n : f.notes) j["notes"].push_back(n);

    const auto t2 = std::chrono::steady_clock::now();
    std::string stroke = "none";
    bool touching = false;
    std::optional<core::GridPoint> control;
    if (f.tipValid) {
      ++s.framesWithTip;
      const Eigen::Vector3d p = f.tipPlanet * scale;
      j["tip_planet_m"] = vec(f.tipPlanet);
      j["tip_height_mm"] = std::round(f.tipHeight * 1e6) / 1e3;
      if (f.tipHeld) j["tip_held"] = true;
      touching = f.touching && p.allFinite() && p.norm() > 0;
      if (touching) {
        ++s.touchingFrames;
        const auto c = edit::nearestVertex(chart, p);
        control = c;
        j["control_vertex"] = {c.u, c.v};
        const edit::ToolInput input{toolPosition(p, c, !pipeline.inStroke()),
                                    std::max(0.0, time - lastTime)};
        try {
          if (!pipeline.inStroke()) {
            const auto r = pipeline.beginStroke(tool, input);
            ++s.strokes;
            ++s.stamps;
            s.modifiedVertices += r.modifiedVertices;
            j["stamps"] = 1;
            j["modified_vertices"] = r.modifiedVertices;
            stroke = "begin";
          } else {
            const auto r = pipeline.moveTo(input);
            s.stamps += r.stamps;
            s.modifiedVertices += r.modifiedVertices;
            j["stamps"] = r.stamps;
            j["modified_vertices"] = r.modifiedVertices;
            stroke = "move";
          }
        } catch (const core::InputError& e) {
          ++s.skippedFrames;
          j["notes"].push_back(std::string("edit skipped: ") + e.what());
        }
      }
    }
    if (!touching && pipeline.inStroke()) {
      pipeline.endStroke();
      stroke = "end";
    }
    j["touching"] = touching;
    j["stroke"] = stroke;
    if (settler) {
      const auto r = settler->frame();
      s.settleCellSteps += r.cellSteps;
      s.settleFramesAtRest += r.atRest;
      if (r.steps > 0) j["settle_steps"] = r.steps;
    }
    editMs = msSince(t2);
    lastTime = time;
    if (hook) {
      std::optional<tracking::Pose> planetPose;
      if (f.planet.usable()) planetPose = scene.planetFromMarker(f.planet.pose);
      const FrameContext ctx{frame, time,       image,    f,       calib,        planet,
                             scale, planetPose, touching, control, tool.radius()};
      hook(ctx);
    }
    log << j.dump() << "\n";
    if (timings)
      *timings << nlohmann::json{{"frame", frame},
                                 {"detect_ms", std::round(detectMs * 1000) / 1000},
                                 {"track_ms", std::round(trackMs * 1000) / 1000},
                                 {"edit_ms", std::round(editMs * 1000) / 1000}}
                      .dump()
               << "\n";
    ++s.frames;
    if (progress) progress(s.frames, source.announcedFrames());
  }
  if (pipeline.inStroke()) pipeline.endStroke();
  s.truncated = source.truncated();
  if (s.truncated)
    s.warnings.push_back(
        source.name() + ": the video ended at frame " + std::to_string(s.frames) + " of the " +
        std::to_string(s.announcedFrames) +
        " its container announced (truncated or corrupt); replayed what was there");
  if (!anyMarker)
    s.warnings.push_back(source.name() + ": no marker of " + dc.family + " with id " +
                         std::to_string(o.scene.planet.id) + " or " +
                         std::to_string(o.scene.tool.id) + " was ever seen; nothing was sculpted");
  else if (s.framesWithPlanet == 0)
    s.warnings.push_back(source.name() + ": the planet marker (id " +
                         std::to_string(o.scene.planet.id) + ") was never seen");
  else if (s.framesWithTool == 0)
    s.warnings.push_back(source.name() + ": the tool marker (id " +
                         std::to_string(o.scene.tool.id) + ") was never seen");
  if (s.skippedFrames > 0)
    s.warnings.push_back(std::to_string(s.skippedFrames) +
                         " frame(s) had their edit refused; the log's notes say why");
  return s;
}

}  // namespace ps::replay
