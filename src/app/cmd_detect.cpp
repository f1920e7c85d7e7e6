// `planetsculpt detect IMAGE|FOLDER|VIDEO`: the user's first check that printed markers work.
// One JSON object per marker on stdout: frame, id, corners (TL, TR, BR, BL, OpenCV pixel
// convention) and, with --calib, the pose (rvec/tvec of the marker in the camera frame, metres).
#include <algorithm>
#include <cmath>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>

#include "app/command_registry.hpp"
#include "core/input_error.hpp"
#include "tracking/calibration.hpp"
#include "tracking/detector.hpp"
#include "tracking/pose.hpp"
#include "tracking/video.hpp"

namespace ps::app {

namespace {

struct DetectArgs {
  std::string input, calib, backend = "auto", refine = "contour";
  tracking::DetectorConfig detector;
  double markerSize = 0.05;
  int maxFrames = 0;
  bool decimateGiven = false;
};

// Still images have no frame budget, and small markers in them are found more often on the
// full-size image: on synthetic 1280x960 stills of the board and the cube (tags 12-40 px),
// decimate 1 found 343 of 407 board markers and 54 cube faces where decimate 2 found 334 and
// 45, for 19 % more time (docs/TRACKING.md). Videos keep the live path's decimation.
constexpr double kStillImageDecimate = 1.0;

double round3(double v) {
  return std::round(v * 1000.0) / 1000.0;
}
double round6(double v) {
  return std::round(v * 1e6) / 1e6;
}

int runDetect(DetectArgs& a) {
  a.detector.backend = tracking::backendFromString(a.backend);
  a.detector.arucoRefinement = tracking::arucoRefinementFromString(a.refine);
  if (!(a.markerSize > 0) || !std::isfinite(a.markerSize))
    throw core::InputError("--marker-size " + std::to_string(a.markerSize) + " m is not > 0");
  tracking::FrameSource source(a.input);
  if (!source.isVideo() && !a.decimateGiven) a.detector.decimate = kStillImageDecimate;
  // --family A,B: every family listed, each marker's JSON naming its family.
  std::vector<tracking::DetectorConfig> families;
  for (std::size_t start = 0; start <= a.detector.family.size();) {
    const std::size_t comma =
        std::min(a.detector.family.find(',', start), a.detector.family.size());
    families.push_back(a.detector);
    families.back().family = a.detector.family.substr(start, comma - start);
    start = comma + 1;
  }
  const bool manyFamilies = families.size() > 1;
  auto detector = tracking::makeDetector(families);
  std::unique_ptr<tracking::CameraCalibration> calib;
  if (!a.calib.empty())
    calib = std::make_unique<tracking::CameraCalibration>(
        tracking::loadCalibration(a.calib).forImageSize(source.size()));
  std::cerr << "detect: " << detector->name() << " on " << source.name() << " ("
            << source.size().width << "x" << source.size().height << ")\n";
  cv::Mat frame;
  long long markers = 0;
  int frames = 0, framesWithMarkers = 0;
  while ((a.maxFrames <= 0 || frames < a.maxFrames) && source.read(frame)) {
    ++frames;
    if (frame.size() != source.size())
      throw core::InputError(source.frameName() + ": image size differs from the first one");
    const auto found = detector->detect(frame);
    if (!found.empty()) ++framesWithMarkers;
    for (std::size_t i = 0; i < found.size(); ++i) {
      const auto& d = found[i];
      nlohmann::json j = {{"frame", source.index()}, {"id", d.id}};
      if (manyFamilies) j["family"] = d.family;
      if (!source.isVideo() && source.announcedFrames() > 1) j["file"] = source.frameName();
      nlohmann::json corners = nlohmann::json::array();
      for (const auto& c : d.corners) corners.push_back({round3(c.x), round3(c.y)});
      j["corners"] = corners;
      auto same = [&](std::size_t k) { return found[k].id == d.id && found[k].family == d.family; };
      const bool twice = (i > 0 && same(i - 1)) || (i + 1 < found.size() && same(i + 1));
      if (twice) j["duplicate_id"] = true;
      if (calib) {
        const auto cands = tracking::solveMarkerPose(d.corners, a.markerSize, *calib);
        const auto choice = tracking::choosePose(cands, nullptr, 0);
        if (choice.valid) {
          const Eigen::Vector3d r = choice.pose.rvec(), t = choice.pose.t;
          j["rvec"] = {round6(r.x()), round6(r.y()), round6(r.z())};
          j["tvec"] = {round6(t.x()), round6(t.y()), round6(t.z())};
          j["reprojection_px"] = round3(cands.rms[0]);
          if (cands.count == 2) j["ambiguity_ratio"] = round3(choice.ratio);
        } else {
          j["pose_error"] = "the solver found no finite pose";
        }
      }
      std::cout << j.dump() << "\n";
      ++markers;
    }
  }
  if (source.truncated())
    std::cerr << "detect: " << source.name() << ": the video ended at frame " << frames
              << " of the " << source.announcedFrames()
              << " its container announced (truncated or corrupt)\n";
  std::cerr << "detect: " << markers << " marker(s) in " << framesWithMarkers << " of " << frames
            << " frame(s)\n";
  if (markers == 0) {
    std::cerr << "detect: no " << a.detector.family << " marker found in " << source.name()
              << " (another family? try --family DICT_6X6_250, or a larger, sharper view)\n";
    return 1;
  }
  return 0;
}

const CommandRegistration kDetect([](CLI::App& root, CLI::App*& sub) -> CommandAction {
  auto a = std::make_shared<DetectArgs>();
  sub = root.add_subcommand("detect",
                            "Detect markers in an image, image folder or video; JSON lines");
  sub->add_option("input", a->input, "Image, folder of images, or video")->required();
  sub->add_option("--family", a->detector.family,
                  "Marker family as the libraries name it (tag36h11, DICT_6X6_250, ...); "
                  "several, comma-separated, to detect each")
      ->capture_default_str();
  sub->add_option("--detector", a->backend, "Back end: auto, aruco or apriltag")
      ->capture_default_str();
  sub->add_option("--refine", a->refine, "aruco corner refinement: none, subpix, contour, apriltag")
      ->capture_default_str();
  sub->add_option("--decimate", a->detector.decimate,
                  "AprilTag quad decimation (1 = full size); default 1 for still images, 2 for "
                  "videos");
  sub->add_option("--min-contrast", a->detector.minContrast,
                  "AprilTag: least grey-level difference across a marker edge")
      ->capture_default_str();
  sub->add_option("--ids", a->detector.ids, "Keep only these ids")->delimiter(',');
  sub->add_option("--calib", a->calib, "Camera calibration (OpenCV YAML): adds rvec/tvec");
  sub->add_option("--marker-size", a->markerSize, "Marker edge (black border) in metres")
      ->capture_default_str();
  sub->add_option("--max-frames", a->maxFrames, "Stop after this many frames (0: all)");
  const CLI::Option* decimate = sub->get_option("--decimate");
  return [a, decimate] {
    a->decimateGiven = decimate->count() > 0;
    return runDetect(*a);
  };
});

}  // namespace
}  // namespace ps::app
