#include "app/replay_job.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iostream>
#include <memory>
#include <numbers>
#include <opencv2/imgproc.hpp>
#include <optional>

#include "app/ar_recorder.hpp"
#include "app/default_planet.hpp"
#include "app/plot.hpp"
#include "app/progress.hpp"
#include "app/snapshot.hpp"
#include "core/grid.hpp"
#include "core/input_error.hpp"
#include "haptics/force_path.hpp"
#include "io/heightmap_export.hpp"
#include "io/planet_file.hpp"
#include "replay/session_timeline.hpp"
#include "replay/truth_check.hpp"
#include "sand/displacement.hpp"
#include "terrain/screen_error.hpp"
#include "terrain/tessellator.hpp"

namespace ps::app {

namespace {

void renameInto(const std::filesystem::path& from, const std::filesystem::path& to) {
  std::error_code ec;
  std::filesystem::rename(from, to, ec);
  if (ec) throw std::runtime_error("cannot rename " + from.string() + " to " + to.string());
}

// The vertices the replay changed: their bounding box in pixels of the w x h picture raster
// (pictureRaster), and the vertex whose height changed most (the view looks there). Lat-long's
// and the tubes' rasters follow the grid's (u, v); on the octahedral chart a vertex's pixel is
// its direction's latitude and longitude (its grid is folded, every column a point of its own).
struct Change {
  bool any = false;
  cv::Rect box;
  int u = 0, v = 0;
  double largest = 0;
};

Change findChange(const terrain::Terrain& t, const std::vector<float>& before, int w, int h) {
  Change c;
  const int side = t.grid().side(), m = t.grid().m();
  const bool byDirection = t.chart().sphereRadius() > 0 && !t.chart().hasPoleRows();
  int x0 = w, x1 = -1, y0 = h, y1 = -1;
  const auto now = t.heights();
  for (int v = 0; v < side; ++v) {
    for (int u = 0; u < (byDirection ? side : m); ++u) {
      const std::size_t i = std::size_t(v) * std::size_t(side) + std::size_t(u);
      const double d = std::abs(double(now[i]) - double(before[i]));
      if (d < 1.0) continue;  // metres: float noise of untouched cells is far below this
      c.any = true;
      if (d > c.largest) c = {true, {}, u, v, d};
      int x = int(double(u) / m * w), y = h - 1 - int(double(v) / (side - 1) * (h - 1));
      if (byDirection) {  // column 0 at 180 degrees W, row 0 at the north pole (io::Raster)
        const Eigen::Vector3d dir = t.chart().up(u, v);
        const double lon = std::atan2(dir.y(), dir.x());
        const double lat = std::asin(std::clamp(dir.z(), -1.0, 1.0));
        x = std::clamp(int((0.5 + lon / (2 * std::numbers::pi)) * w), 0, w - 1);
        y = std::clamp(int((0.5 - lat / std::numbers::pi) * h), 0, h - 1);
      }
      x0 = std::min(x0, x), x1 = std::max(x1, x), y0 = std::min(y0, y), y1 = std::max(y1, y);
    }
  }
  if (c.any) c.box = cv::Rect(cv::Point(x0, y0), cv::Point(x1 + 1, y1 + 1));
  return c;
}

// An oblique view of vertex (u, v) from 350 km up and 900 km away.
terrain::Camera viewOf(const terrain::Terrain& t, int u, int v) {
  const Eigen::Vector3d up = t.chart().up(u, v);
  Eigen::Vector3d east = Eigen::Vector3d::UnitZ().cross(up);
  if (east.norm() < 1e-6) east = Eigen::Vector3d::UnitX();
  east.normalize();
  const Eigen::Vector3d north = up.cross(east);
  const double R = t.chart().sphereRadius();
  if (!(R > 0)) {  // a torus or a cylinder: the same view about the vertex's own normal
    const Eigen::Vector3d target = t.chart().position(u, v, t.height(u, v));
    const Eigen::Vector3d eye =
        t.chart().position(u, v, 3.5e5) - 9e5 * (0.8 * north + 0.6 * east).normalized();
    return terrain::Camera::lookAt(eye, target, up, 1280, 720, 60 * std::numbers::pi / 180);
  }
  const Eigen::Vector3d target = (R + t.height(u, v)) * up;
  const Eigen::Vector3d eye = (R + 3.5e5) * up - 9e5 * (0.8 * north + 0.6 * east).normalized();
  return terrain::Camera::lookAt(eye, target, eye.normalized(), 1280, 720,
                                 60 * std::numbers::pi / 180);
}

// The planet's heights as a picture's raster: a sphere's equirectangular, a torus's or a
// cylinder's own (u, v) grid (io::resampleTube; the relief and the close-up read it alike).
io::Raster pictureRaster(const terrain::Terrain& planet, int w, int h) {
  return planet.chart().sphereRadius() > 0 ? io::resampleEquirectangular(planet, w, h)
                                           : io::resampleTube(planet, w, h);
}

cv::Mat labelled(cv::Mat img, const std::string& text) {
  cv::putText(img, text, {12, 30}, cv::FONT_HERSHEY_SIMPLEX, 0.8, {0, 0, 0}, 4, cv::LINE_AA);
  cv::putText(img, text, {12, 30}, cv::FONT_HERSHEY_SIMPLEX, 0.8, {255, 255, 255}, 1, cv::LINE_AA);
  return img;
}

// Before | after, cropped around `box` (padded to a 4:3 window) and scaled to 640 px each.
cv::Mat closeup(const cv::Mat& before, const cv::Mat& after, cv::Rect box) {
  const int pad = std::max(8, std::max(box.width, box.height) / 4);
  box = cv::Rect(box.x - pad, box.y - pad, box.width + 2 * pad, box.height + 2 * pad);
  const int wantW = std::max(box.width, box.height * 4 / 3);
  const int wantH = wantW * 3 / 4;
  box = cv::Rect(box.x + box.width / 2 - wantW / 2, box.y + box.height / 2 - wantH / 2, wantW,
                 wantH) &
        cv::Rect(0, 0, before.cols, before.rows);
  cv::Mat a, b, both;
  cv::resize(before(box), a, {640, 480}, 0, 0, cv::INTER_CUBIC);
  cv::resize(after(box), b, {640, 480}, 0, 0, cv::INTER_CUBIC);
  cv::hconcat(labelled(a, "before"), labelled(b, "after"), both);
  return both;
}

// What a replay runs with once a session sidecar (if any) has had its say.
struct ReplayInputs {
  std::optional<replay::SessionTimeline> timeline;
  std::filesystem::path sidecar;
  replay::ReplayOptions options;
  std::filesystem::path planetFile;
  int gridLevel = 0;
  std::uint64_t seed = 0;
  core::ChartShape chart = kDefaultChart;
  PlanetDims dims;
};

// The sidecar wins over the command line: it holds what the live session ran with.
ReplayInputs resolveInputs(const ReplayJob& job) {
  ReplayInputs in;
  in.sidecar = job.session.empty() ? replay::sessionSidecarPath(job.video) : job.session;
  if (!job.noSession && (!job.session.empty() || std::filesystem::exists(in.sidecar)))
    in.timeline = replay::readSessionTimeline(in.sidecar);
  in.options = job.options;
  in.planetFile = job.planetFile;
  in.gridLevel = job.gridLevel;
  in.seed = job.seed;
  in.chart = job.chart;
  in.dims = job.dims;
  if (!in.timeline) return in;
  const replay::SessionStart& st = in.timeline->start;
  st.applyTo(in.options);
  const replay::SessionSettings& ss = in.timeline->settings;
  in.options.tool = ss.tool;
  in.options.brush = ss.brush;
  in.options.displace = ss.displace;
  in.options.pressDepth = ss.pressDepth;
  in.options.scene.planetRadius = ss.planetRadius;
  in.options.validate();
  if (in.planetFile.empty() && !st.planetFile.empty()) {
    in.planetFile = st.planetFile;
    // Written relative to where `live` ran; a start planet lies beside the sidecar.
    const auto beside = in.sidecar.parent_path() / in.planetFile.filename();
    if (!std::filesystem::exists(in.planetFile) && std::filesystem::exists(beside))
      in.planetFile = beside;
    if (!std::filesystem::exists(in.planetFile))
      throw core::InputError(in.sidecar.string() + ":1: the session started from the planet file " +
                             st.planetFile + ", which is not there (nor beside the sidecar); " +
                             "give it with --planet, or --no-session");
  } else if (in.planetFile.empty()) {
    in.gridLevel = core::GridSize::fromSide(st.gridSide).n();
    in.seed = st.seed;
    in.chart = core::chartShapeFromString(st.chart);
    // Sidecars from before charts were recorded on lat-long, the default then (today's default
    // is kDefaultChart): the replay makes the planet the session sculpted.
    if (!st.chartNamed)
      std::cerr << "replay: the session sidecar " << in.sidecar.string()
                << " names no chart: replaying onto lat-long, the chart of recordings made "
                   "before sidecars named one\n";
    in.dims = {};
    if (st.radius > 0) in.dims.radius = st.radius;
    if (st.minorRadius > 0) in.dims.minorRadius = st.minorRadius;
    if (st.length > 0) in.dims.length = st.length;
  }
  std::cerr << "replay: settings from the session sidecar " << in.sidecar.string() << " ("
            << in.timeline->entries.size() << " changes, undos and redos)\n";
  if (!job.givenOptions.empty()) {
    std::string given;
    for (const auto& o : job.givenOptions) given += (given.empty() ? "" : ", ") + o;
    std::cerr << "replay: warning: " << given
              << " ignored: the session sidecar records what the session ran with "
                 "(--no-session to replay with the options instead)\n";
  }
  return in;
}

// The AR recorder the job asks for; without a GL context, pictures go on without the AR view and
// `noRender` says why (a `--render` job fails instead).
std::unique_ptr<ArRecorder> makeRecorder(const ReplayJob& job, std::string& noRender) {
  if (!job.render && !job.pictures) return nullptr;
  if (job.renderEvery < 1)
    throw core::InputError("--render-every = " + std::to_string(job.renderEvery) +
                           " must be at least 1");
  ArRecorderSettings rs;
  if (job.render) rs.frameDir = job.out / "ar";
  rs.every = job.renderEvery;
  rs.sun = job.sun;
  rs.boardShadow = job.boardShadow;
  rs.atmosphere = job.atmosphere;
  rs.handMask = job.handMask;
  rs.showcase = job.pictures;
  try {
    return std::make_unique<ArRecorder>(rs);
  } catch (const std::runtime_error& e) {
    if (job.render) throw;
    noRender = e.what();  // pictures without the AR view; said in the summary
    return nullptr;
  }
}

// The sculpted planet as a 16-bit heightmap and a planet file; returns the heightmap's size.
cv::Size writeHeightmapAndPlanet(const terrain::Terrain& planet, const std::filesystem::path& out) {
  Progress p("heightmap");
  int hmH = std::min(planet.grid().m(), 4096), hmW = 2 * hmH;
  const core::ChartShape shape = core::shapeOf(planet.chart());
  if (shape == core::ChartShape::kTorus || shape == core::ChartShape::kCylinder) {
    // Its own (u, v) grid, as `export` writes it: m x m (a cylinder m x (m + 1)), every pixel a
    // vertex, so `import --chart torus` takes it back exactly (up to 4096 columns).
    hmW = std::min(planet.grid().m(), 4096);
    hmH = shape == core::ChartShape::kTorus ? hmW : hmW + 1;
    io::writeHeightPng16(io::resampleTube(planet, hmW, hmH), out / "heightmap.png");
  } else {
    io::writeHeightPng16(io::resampleEquirectangular(planet, hmW, hmH), out / "heightmap.png");
  }
  p.update(0.6);
  io::savePlanet(planet, out / "planet.planet");
  p.done((out / "heightmap.png").string() + ", planet.planet");
  return {hmW, hmH};
}

void writeForcePlot(PlotSeries forceSeries, const std::filesystem::path& out) {
  forceSeries.label = "largest force of the frame's 1 kHz ticks";
  forceSeries.colour = seriesColour(3);
  io::writePngAtomically(
      drawPlots({PlotPanel{"Haptic force on the tool tip during the replay (paper 004 sand)",
                           "time (s)",
                           "force (N)",
                           false,
                           false,
                           {forceSeries}}},
                1100, 360),
      out / "forces.png");
}

constexpr int kPictureW = 2048, kPictureH = 1024;

// Relief previews before and after, the close-up of the largest change and a tessellated view of
// it (with its measured screen error in the summary).
void writeReliefPictures(const ReplayJob& job, const terrain::Terrain& planet,
                         const std::vector<float>& before, const io::Raster& beforeRaster,
                         nlohmann::json& summary, nlohmann::json& files) {
  const std::filesystem::path& out = job.out;
  Progress p("pictures");
  const int w = kPictureW, h = kPictureH;
  // Metres per pixel along the picture's rows: half a great circle over h on a sphere; on a
  // torus or a cylinder its circumference round the axis over w (the hill shading's scale).
  const double R = planet.chart().sphereRadius();
  const double mpp = R > 0 ? std::numbers::pi * R / h
                           : 2 * std::numbers::pi * core::dimsOf(planet.chart()).radius / w;
  const cv::Mat after = io::reliefImage(pictureRaster(planet, w, h), mpp);
  const cv::Mat beforeImg = io::reliefImage(beforeRaster, mpp);
  p.update(0.3);
  cv::Mat small;
  cv::resize(after, small, {1024, 512}, 0, 0, cv::INTER_AREA);
  io::writePngAtomically(small, out / "relief.png");
  cv::resize(beforeImg, small, {1024, 512}, 0, 0, cv::INTER_AREA);
  io::writePngAtomically(small, out / "relief_before.png");
  files.push_back("relief.png");
  files.push_back("relief_before.png");
  const Change change = findChange(planet, before, w, h);
  int vu = 0, vv = planet.grid().side() / 2;
  if (change.any) {
    io::writePngAtomically(closeup(beforeImg, after, change.box), out / "closeup.png");
    files.push_back("closeup.png");
    vu = change.u, vv = change.v;
    summary["largest_change_m"] = change.largest;
    // Where the close-up looks, in the picture raster's pixels (x, y, width, height of w x h),
    // and on a sphere where the largest change is: the close-up must frame it.
    summary["closeup_box_px"] = {change.box.x, change.box.y, change.box.width, change.box.height};
    summary["picture_px"] = {w, h};
    if (R > 0) {
      const Eigen::Vector3d d = planet.chart().up(vu, vv);
      summary["largest_change_lat_lon_deg"] = {
          std::asin(std::clamp(d.z(), -1.0, 1.0)) * 180 / std::numbers::pi,
          std::atan2(d.y(), d.x()) * 180 / std::numbers::pi};
    }
  }
  p.update(0.6);
  const terrain::Camera cam = viewOf(planet, vu, vv);
  terrain::Tessellator tess;
  terrain::TessellationSettings ts;
  ts.distMaxPx = job.distMaxPx;
  ts.triangleBudget = job.triangleBudget;
  const auto& mesh = tess.tessellate(planet, cam, ts);
  const auto err = terrain::measureScreenError(planet, cam, mesh);
  io::writePngAtomically(renderSnapshot(planet, mesh, cam, false), out / "view.png");
  io::writePngAtomically(renderSnapshot(planet, mesh, cam, true), out / "view_wireframe.png");
  files.push_back("view.png");
  files.push_back("view_wireframe.png");
  summary["view"] = {{"triangles", mesh.triangleCount()},
                     {"dist_max_px", ts.distMaxPx},
                     {"effective_dist_max_px", tess.stats().effectiveDistMaxPx},
                     {"measured_max_screen_error_px", err.maxPx}};
  p.done(std::to_string(mesh.triangleCount()) + " triangles in view");
}

// A synthetic recording's ground truth (VIDEO.truth.jsonl, from `synth`) beside the video: the
// replay's log compared with it (replay/truth_check.hpp). A truth file that does not read is a
// warning, not a failed replay: the sculpting did not depend on it.
nlohmann::json compareWithTruthBeside(const std::filesystem::path& video,
                                      const std::filesystem::path& logPath,
                                      std::vector<std::string>& warnings) {
  const std::filesystem::path truthPath = replay::truthPathFor(video);
  if (!std::filesystem::exists(truthPath)) return nullptr;
  std::ifstream truth(truthPath), log(logPath);
  try {
    nlohmann::json j =
        replay::compareWithTruth(truth, truthPath.string(), log, logPath.string()).toJson();
    j["file"] = truthPath.string();
    return j;
  } catch (const core::InputError& e) {
    warnings.push_back(std::string("ground truth not compared: ") + e.what());
    return nullptr;
  }
}

// The planet the replay sculpts: the job's file or the default one, checked against the session
// sidecar's start (another start planet or calibration would sculpt another planet).
std::unique_ptr<terrain::Terrain> startPlanet(const ReplayInputs& in,
                                              const tracking::CameraCalibration& calib) {
  std::unique_ptr<terrain::Terrain> planet =
      in.planetFile.empty() ? makeDefaultPlanet(in.gridLevel, in.seed, in.chart, in.dims)
                            : io::loadPlanet(in.planetFile);
  if (!(core::boundingRadius(planet->chart()) > 0))
    throw core::InputError(in.planetFile.string() + ": a " + planet->chart().name() +
                           " planet has no centre to stand on the planet board (a sphere, a "
                           "torus or a cylinder does)");
  if (in.timeline) replay::checkSessionStart(*in.timeline, *planet, calib);
  return planet;
}

// The haptic force path run beside the replay, its log written to OUT/forces.csv.
struct ForceRecording {
  std::unique_ptr<haptics::ForcePath> path;
  std::ofstream csv;
  bool here = false;  // forces.csv is written
  double peak = 0;
  PlotSeries series;  // per frame: time, the largest force of its ticks
  std::size_t rows = 0;

  // The force path presses with the sand core's displacement tool: none on a chart the sand
  // core does not know, nor on a grid whose cells are wider than the tool; the replay goes on
  // without forces, saying so.
  void start(const ReplayJob& job, terrain::Terrain& planet, double planetRadius) {
    here = job.forces && sand::sandCoreKnows(planet.chart());
    if (job.forces && !here)
      std::cerr << "replay: no forces.csv: the haptic path's press tool (the sand core) does not "
                   "work on the "
                << planet.chart().name() << " chart\n";
    haptics::ForcePathConfig hc;
    if (here && hc.press.displacement.radius < sand::largestSpacing(planet.chart())) {
      here = false;
      std::cerr << "replay: no forces.csv: the haptic path's press tool (radius "
                << hc.press.displacement.radius << " m) is below one cell of this grid ("
                << sand::largestSpacing(planet.chart()) << " m)\n";
    }
    if (!here) return;
    hc.map.scale = core::boundingRadius(planet.chart()) / planetRadius;
    csv.open(job.out / "forces.csv.part");
    if (!csv) throw std::runtime_error("cannot write in " + job.out.string());
    path = std::make_unique<haptics::ForcePath>(planet, nullptr, hc);
    path->setLog(&csv);
  }

  // One frame: the force the tool felt and where (zero when not touching).
  void onFrame(const replay::FrameContext& f, Eigen::Vector3d& force, Eigen::Vector3d& forceTip) {
    if (!path) return;
    std::optional<Eigen::Vector3d> tip;
    if (f.scene.tipValid) tip = f.scene.tipPlanet * f.scale;
    // The sand TIN tool's region is felt as it is drawn: at the TIN's own detail.
    path->setSurface(f.patch);
    const auto ff = path->onFrame(tip, f.time);
    peak = std::max(peak, ff.maxForce);
    series.x.push_back(f.time);
    series.y.push_back(ff.maxForce);
    // The workspace map is the identity rotation: device directions are planet directions.
    if (ff.last && ff.last->touching && ff.last->tipPlanet.allFinite()) {
      force = ff.last->force;
      forceTip = ff.last->tipPlanet;
    }
  }

  void finish(const std::filesystem::path& out) {
    if (!path) return;
    rows = path->logRows();
    path->setLog(nullptr);
    path.reset();
    csv.close();
    renameInto(out / "forces.csv.part", out / "forces.csv");
  }
};

// Every frame of the video through the stepper, with the force path and the AR recorder on
// each; the log and timings written to OUT.
replay::ReplaySummary runFrames(const ReplayJob& job, tracking::FrameSource& source,
                                const tracking::CameraCalibration& calib, terrain::Terrain& planet,
                                const ReplayInputs& in, ForceRecording& forces,
                                ArRecorder* recorder) {
  const std::filesystem::path& out = job.out;
  std::ofstream log(out / "log.jsonl.part"), timings(out / "timings.jsonl.part");
  if (!log || !timings) throw std::runtime_error("cannot write in " + out.string());
  Progress p("replay " + job.video.filename().string());
  replay::FrameHook hook = [&](const replay::FrameContext& f) {
    Eigen::Vector3d force = Eigen::Vector3d::Zero(), forceTip = Eigen::Vector3d::Zero();
    forces.onFrame(f, force, forceTip);
    if (recorder) recorder->onFrame(f, force, forceTip);
  };
  replay::ReplaySummary s = replay::runReplay(
      source, calib, planet, in.options, log, &timings,
      [&](int f, int total) {
        p.update(total > 0 ? double(f) / total : 0.0, std::to_string(f) + " frames");
      },
      hook, in.timeline ? &*in.timeline : nullptr);
  if (in.timeline && !in.timeline->warning.empty()) s.warnings.push_back(in.timeline->warning);
  p.done(std::to_string(s.frames) + " frames, " + std::to_string(s.strokes) + " strokes, " +
         std::to_string(s.stamps) + " stamps");
  log.close();
  timings.close();
  renameInto(out / "log.jsonl.part", out / "log.jsonl");
  renameInto(out / "timings.jsonl.part", out / "timings.jsonl");
  return s;
}

// summary.json's figures of the replay and the planet it left.
nlohmann::json replaySummary(const ReplayJob& job, const ReplayInputs& in,
                             const replay::ReplaySummary& s, const terrain::Terrain& planet,
                             const ForceRecording& forces, cv::Size heightmap) {
  nlohmann::json summary = {
      {"video", job.video.string()},
      {"calibration", job.calibration.string()},
      {"tool", replay::toString(in.options.tool)},
      {"material", in.options.displace.material.name},
      {"session", in.timeline ? in.sidecar.string() : ""},
      {"session_changes", s.sessionChanges},
      {"frames", s.frames},
      {"announced_frames", s.announcedFrames},
      {"truncated", s.truncated},
      {"frames_with_planet", s.framesWithPlanet},
      {"planet_tracked", s.framesWithPlanet - s.framesPlanetHeld},
      {"planet_held", s.framesPlanetHeld},
      {"planet_lost", s.frames - s.framesWithPlanet},
      {"frames_with_tool", s.framesWithTool},
      {"frames_with_tip", s.framesWithTip},
      {"touching_frames", s.touchingFrames},
      {"strokes", s.strokes},
      {"stamps", s.stamps},
      {"modified_vertices", s.modifiedVertices},
      {"skipped_frames", s.skippedFrames},
      {"settle_cell_steps", s.settleCellSteps},
      {"force_ticks", forces.rows},
      {"peak_force_n", forces.peak},
      {"warnings", s.warnings},
      {"grid", planet.grid().label()},
      {"chart", planet.chart().name()},
      {"radius_m", core::dimsOf(planet.chart()).radius},  // a torus's major radius
      {"heightmap", {{"width", heightmap.width}, {"height", heightmap.height}}}};
  if (const core::ChartDims d = core::dimsOf(planet.chart()); d.minorRadius > 0)
    summary["minor_radius_m"] = d.minorRadius;
  else if (d.length > 0)
    summary["length_m"] = d.length;
  return summary;
}

// The AR recorder's figures and pictures into the summary and the file list.
void addRecorderOutputs(const ReplayJob& job, ArRecorder* recorder, const std::string& noRender,
                        nlohmann::json& summary, nlohmann::json& files) {
  if (!recorder) {
    if (!noRender.empty()) {
      summary["ar_view_skipped"] = noRender;
      std::cerr << "replay: no AR pictures: " << noRender << "\n";
    }
    return;
  }
  summary["renderer"] = recorder->renderer();
  summary["render_ms"] = recorder->renderMsTotal();
  if (recorder->strokeTinFrames() > 0)
    summary["ar_stroke_tin_frames"] = recorder->strokeTinFrames();
  // AR frames drawn with the camera image over part of the planet (a hand in front of it).
  summary["ar_hand_mask_frames"] = recorder->handMaskFrames();
  if (job.render) {
    summary["ar_frames"] = recorder->framesWritten();
    files.push_back("ar/");
  }
  if (job.pictures && recorder->writeShowcase(job.out)) {
    files.push_back("ar_view.png");
    files.push_back("overview.png");
  }
}

}  // namespace

nlohmann::json runReplayJob(const ReplayJob& job) {
  job.options.validate();
  // Inputs first: a bad video, calibration or sidecar costs nothing.
  tracking::FrameSource source(job.video.string());
  const auto calib = tracking::loadCalibration(job.calibration);
  calib.forImageSize(source.size());  // refuses another aspect ratio, naming the file
  const ReplayInputs in = resolveInputs(job);
  std::unique_ptr<terrain::Terrain> planet = startPlanet(in, calib.forImageSize(source.size()));
  const std::vector<float> before(planet->heights().begin(), planet->heights().end());
  // The pictures' "before" raster, resampled now rather than from a rebuilt terrain afterwards.
  io::Raster beforeRaster;
  if (job.pictures) beforeRaster = pictureRaster(*planet, kPictureW, kPictureH);

  std::string noRender;
  std::unique_ptr<ArRecorder> recorder = makeRecorder(job, noRender);
  const std::filesystem::path& out = job.out;
  std::filesystem::create_directories(out);
  ForceRecording forces;
  forces.start(job, *planet, in.options.scene.planetRadius);
  replay::ReplaySummary s = runFrames(job, source, calib, *planet, in, forces, recorder.get());
  const nlohmann::json truth = compareWithTruthBeside(job.video, out / "log.jsonl", s.warnings);
  forces.finish(out);

  nlohmann::json files = {"heightmap.png", "heightmap.png.json", "planet.planet", "log.jsonl",
                          "timings.jsonl"};
  if (forces.here) files.push_back("forces.csv");
  const cv::Size heightmap = writeHeightmapAndPlanet(*planet, out);
  nlohmann::json summary = replaySummary(job, in, s, *planet, forces, heightmap);
  if (!truth.is_null()) summary["truth"] = truth;
  addRecorderOutputs(job, recorder.get(), noRender, summary, files);
  if (job.pictures && forces.here && !forces.series.x.empty()) {
    writeForcePlot(forces.series, out);
    files.push_back("forces.png");
  }
  if (job.pictures) writeReliefPictures(job, *planet, before, beforeRaster, summary, files);
  summary["files"] = files;
  std::ofstream(out / "summary.json") << summary.dump(2) << "\n";
  for (const auto& w : s.warnings) std::cerr << "replay: warning: " << w << "\n";
  return summary;
}

}  // namespace ps::app
