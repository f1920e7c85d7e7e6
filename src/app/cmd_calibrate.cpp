// `planetsculpt calibrate INPUT --out FILE`: camera calibration from views of the ChArUco board
// that `planetsculpt markers` prints, or of a plain chessboard (--pattern chessboard). INPUT is a
// video file, an image folder (or one image), or a camera index (0, 1, ...). Progress lines on
// stderr say which views were kept and how much of the image the corners have covered (a coarse
// grid: the empty cells are where the board should go next); at the end, the RMS reprojection error
// and the intrinsics' standard deviations. A calibration that misses a threshold is not written
// (exit code 2), with the reasons. A summary JSON object goes to stdout.
#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <opencv2/videoio.hpp>
#include <sstream>
#include <tuple>

#include "app/command_registry.hpp"
#include "core/input_error.hpp"
#include "tracking/charuco_calibration.hpp"
#include "tracking/chessboard_calibration.hpp"
#include "tracking/video.hpp"

namespace ps::app {

namespace {

struct CalibrateArgs {
  std::string input, out = "camera.yml", squares = "5x7", pattern = "charuco";
  double squareMm = 30, markerMm = 22;
  std::string dictionary = "DICT_5X5_100";
  tracking::CalibrationThresholds thresholds;
  double minShift = -1;  // -1: 20 px for video and cameras, 0 for images
  int every = 1;
  int maxFrames = 0;
  int targetViews = 30;  // cameras: stop when this many views cover enough of the image
  bool k3 = false, fixAspect = false, zeroTangent = false;
  bool squaresGiven = false, markerOptionGiven = false;
};

bool isCameraIndex(const std::string& s) {
  return !s.empty() && s.size() <= 2 && std::all_of(s.begin(), s.end(), [](char c) {
    return std::isdigit(static_cast<unsigned char>(c));
  });
}

std::string fixed(double v, int digits) {
  std::ostringstream s;
  s.setf(std::ios::fixed);
  s.precision(digits);
  s << v;
  return s.str();
}

// --squares COLUMNSxROWS.
std::pair<int, int> squaresFrom(const CalibrateArgs& a) {
  std::pair<int, int> b;
  const auto x = a.squares.find('x');
  try {
    if (x == std::string::npos) throw std::invalid_argument("no x");
    std::size_t used = 0;
    b.first = std::stoi(a.squares.substr(0, x), &used);
    if (used != x) throw std::invalid_argument("columns");
    const std::string rows = a.squares.substr(x + 1);
    b.second = std::stoi(rows, &used);
    if (used != rows.size()) throw std::invalid_argument("rows");
  } catch (const std::exception&) {
    throw core::InputError("--squares '" + a.squares + "' is not COLUMNSxROWS (e.g. 5x7)");
  }
  return b;
}

tracking::CharucoBoardSpec boardFrom(const CalibrateArgs& a) {
  tracking::CharucoBoardSpec b;
  std::tie(b.squaresX, b.squaresY) = squaresFrom(a);
  b.squareLength = a.squareMm * 1e-3;
  b.markerLength = a.markerMm * 1e-3;
  b.dictionary = a.dictionary;
  b.validate();
  return b;
}

void printCoverage(const tracking::Coverage& c) {
  std::cerr << "calibrate: coverage (# corners seen, . none yet):\n";
  for (const auto& row : c.map()) std::cerr << "    " << row << "\n";
}

// The views from the input into `make`'s calibrator (ChArUco or chessboard: the same methods),
// then the calibration judged and written. `target` describes the board, `check` names the
// options that describe it.
template <class Make>
int calibrateWith(CalibrateArgs& a, Make make, const std::string& target,
                  const std::string& check) {
  const bool camera = isCameraIndex(a.input) && !std::filesystem::exists(a.input);
  std::unique_ptr<tracking::FrameSource> source;
  cv::VideoCapture capture;
  bool video = camera;
  if (camera) {
    if (!capture.open(std::stoi(a.input)))
      throw core::InputError("camera " + a.input + ": cannot open it (is it connected?)");
  } else {
    source = std::make_unique<tracking::FrameSource>(a.input);
    video = source->isVideo();
  }
  if (a.minShift < 0) a.minShift = video ? 20.0 : 0.0;
  a.thresholds.minViewShiftPx = a.minShift;
  if (a.every < 1) throw core::InputError("--every must be >= 1");
  tracking::CalibrationFlags flags;
  flags.fixK3 = !a.k3;
  flags.fixAspect = a.fixAspect;
  flags.zeroTangent = a.zeroTangent;
  auto calibrator = make(a.thresholds, flags);
  std::cerr << "calibrate: " << target << "; " << (camera ? "camera " + a.input : source->name())
            << "\n";

  cv::Mat frame;
  int frames = 0, withBoard = 0, lastCoveragePrint = 0;
  auto lastLine = std::chrono::steady_clock::now();
  while (a.maxFrames <= 0 || frames < a.maxFrames) {
    const bool ok = camera ? capture.read(frame) : source->read(frame);
    if (!ok || frame.empty()) break;
    const int index = frames++;
    if (index % a.every != 0) continue;
    const std::string name = camera  ? "camera frame " + std::to_string(index)
                             : video ? source->name() + " frame " + std::to_string(index)
                                     : source->frameName();
    const auto v = calibrator.addImage(frame, name);
    if (v.corners > 0) ++withBoard;
    const auto& cov = calibrator.coverage();
    const auto now = std::chrono::steady_clock::now();
    if (v.kept) {
      std::cerr << "calibrate: view " << calibrator.views() << " kept (" << name
                << "): " << v.corners << " corners; coverage " << cov.covered() << "/"
                << cov.counts.size() << " cells (" << fixed(100 * cov.fraction(), 0) << " %)\n";
      lastLine = now;
      if (calibrator.views() - lastCoveragePrint >= 10) {
        printCoverage(cov);
        lastCoveragePrint = calibrator.views();
      }
    } else if (!video || now - lastLine > std::chrono::seconds(3)) {
      std::cerr << "calibrate: " << name << ": not kept ("
                << (v.reason.empty() ? std::string("no board") : v.reason) << ", "
                << (a.pattern == "charuco" ? std::to_string(v.markers) + " markers, " : "")
                << v.corners << " corners)\n";
      lastLine = now;
    }
    if (calibrator.full()) break;
    if (camera && calibrator.views() >= a.targetViews && cov.fraction() >= a.thresholds.minCoverage)
      break;
  }
  if (source && source->truncated())
    std::cerr << "calibrate: " << source->name() << ": the video ended at frame " << frames
              << " of the " << source->announcedFrames() << " its container announced\n";
  std::cerr << "calibrate: " << calibrator.views() << " view(s) kept of " << frames
            << " frame(s); the board's corners were found in " << withBoard << "\n";
  if (calibrator.views() == 0)
    throw core::InputError((camera ? "camera " + a.input : source->name()) + ": the " + target +
                           " was never seen with enough corners; check " + check +
                           " against the printed board");
  if (lastCoveragePrint != calibrator.views()) printCoverage(calibrator.coverage());
  const tracking::CalibrationResult res = calibrator.calibrate();
  const auto& K = res.calibration.K;
  std::cerr << "calibrate: RMS reprojection error " << fixed(res.rms, 3) << " px over " << res.views
            << " views, " << res.corners << " corners\n";
  const char* names[9] = {"fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2", "k3"};
  const double values[4] = {K(0, 0), K(1, 1), K(0, 2), K(1, 2)};
  for (std::size_t i = 0; i < res.stdDeviations.size() && i < 9; ++i) {
    const double v = i < 4 ? values[i] : res.calibration.distortion.at<double>(int(i) - 4);
    std::cerr << "calibrate:   " << names[i] << " = " << fixed(v, i < 4 ? 2 : 5) << " +- "
              << fixed(res.stdDeviations[i], i < 4 ? 2 : 5)
              << (i == 8 && !a.k3 ? " (fixed; --k3 to estimate it)" : "") << "\n";
  }
  nlohmann::json j = {
      {"rms_px", res.rms},
      {"views", res.views},
      {"corners", res.corners},
      {"coverage", res.coverage},
      {"image_width", calibrator.imageSize().width},
      {"image_height", calibrator.imageSize().height},
      {"camera_matrix", {K(0, 0), K(0, 1), K(0, 2), K(1, 0), K(1, 1), K(1, 2), 0, 0, 1}},
      {"std_deviations_intrinsics", res.stdDeviations},
      {"problems", res.problems}};
  std::vector<double> dist;
  for (int i = 0; i < int(res.calibration.distortion.total()); ++i)
    dist.push_back(res.calibration.distortion.at<double>(i));
  j["distortion_coefficients"] = dist;
  if (!res.acceptable) {
    std::cerr << "calibrate: NOT WRITTEN: this calibration is poor:\n";
    for (const auto& p : res.problems) std::cerr << "  - " << p << "\n";
    std::cerr << "calibrate: thresholds: RMS <= " << a.thresholds.maxRmsPx
              << " px, >= " << a.thresholds.minViews
              << " views, coverage >= " << fixed(100 * a.thresholds.minCoverage, 0) << " % of a "
              << a.thresholds.gridColumns << "x" << a.thresholds.gridRows
              << " grid, std fx/fy <= " << fixed(100 * a.thresholds.maxFocalStdRel, 1)
              << " %, std cx/cy <= " << fixed(100 * a.thresholds.maxCentreStdRel, 1)
              << " % of the width\n";
    j["written"] = false;
    std::cout << j.dump() << "\n";
    return 2;
  }
  const std::filesystem::path out = a.out;
  if (out.has_parent_path()) std::filesystem::create_directories(out.parent_path());
  tracking::saveCalibrationResult(res, target, out);
  std::cerr << "calibrate: wrote " << out.string() << "\n";
  j["written"] = true;
  j["file"] = out.string();
  std::cout << j.dump() << "\n";
  return 0;
}

int runCalibrate(CalibrateArgs& a) {
  if (a.pattern == "charuco") {
    const tracking::CharucoBoardSpec board = boardFrom(a);
    return calibrateWith(
        a,
        [&](const tracking::CalibrationThresholds& t, tracking::CalibrationFlags f) {
          return tracking::CharucoCalibrator(board, t, f);
        },
        "ChArUco board " + board.describe(),
        "--squares, --square-mm, --marker-mm and --dictionary");
  }
  if (a.pattern != "chessboard")
    throw core::InputError("--pattern '" + a.pattern + "' is not charuco or chessboard");
  if (!a.squaresGiven)
    throw core::InputError(
        "--pattern chessboard needs --squares COLUMNSxROWS, the squares as printed (8x6 squares "
        "have 7x5 inner corners; OpenCV's pattern.png is 10x7)");
  if (a.markerOptionGiven)
    throw core::InputError(
        "--marker-mm and --dictionary describe a ChArUco board; a chessboard has no markers");
  tracking::ChessboardSpec board;
  std::tie(board.squaresX, board.squaresY) = squaresFrom(a);
  board.squareLength = a.squareMm * 1e-3;
  board.validate();
  return calibrateWith(
      a,
      [&](const tracking::CalibrationThresholds& t, tracking::CalibrationFlags f) {
        return tracking::ChessboardCalibrator(board, t, f);
      },
      "chessboard " + board.describe(), "--squares and --square-mm");
}

const CommandRegistration kCalibrate([](CLI::App& root, CLI::App*& sub) -> CommandAction {
  auto a = std::make_shared<CalibrateArgs>();
  sub = root.add_subcommand(
      "calibrate",
      "Calibrate a camera from a ChArUco board or a plain chessboard (video, image folder or "
      "camera index); refuses a poor calibration");
  sub->add_option("input", a->input, "Video file, image folder, image, or camera index (0, 1, ..)")
      ->required();
  sub->add_option("--out", a->out, "Calibration file to write (OpenCV YAML)")
      ->capture_default_str();
  sub->add_option("--squares", a->squares,
                  "Board squares, COLUMNSxROWS (ChArUco: rows odd; a chessboard of 8x6 squares "
                  "has 7x5 inner corners)")
      ->capture_default_str();
  sub->add_option("--square-mm", a->squareMm, "Chessboard square edge as printed (mm)")
      ->capture_default_str();
  sub->add_option("--marker-mm", a->markerMm, "ArUco marker edge as printed (mm)")
      ->capture_default_str();
  sub->add_option("--dictionary", a->dictionary, "The board's ArUco dictionary")
      ->capture_default_str();
  sub->add_option("--min-views", a->thresholds.minViews, "Refuse with fewer views")
      ->capture_default_str();
  sub->add_option("--max-views", a->thresholds.maxViews, "Stop collecting at this many views")
      ->capture_default_str();
  sub->add_option("--max-rms", a->thresholds.maxRmsPx, "Refuse above this RMS error (px)")
      ->capture_default_str();
  sub->add_option("--min-coverage", a->thresholds.minCoverage,
                  "Refuse when the corners covered less of the image grid (0..1)")
      ->capture_default_str();
  sub->add_option("--min-corners", a->thresholds.minCornersPerView,
                  "Chessboard corners for a view to count")
      ->capture_default_str();
  sub->add_option("--min-shift", a->minShift,
                  "Mean corner motion (px) since the last kept view (default: 20 for video and "
                  "cameras, 0 for images)");
  sub->add_option("--every", a->every, "Look at every Nth frame")->capture_default_str();
  sub->add_option("--max-frames", a->maxFrames, "Stop after this many frames (0: all)");
  sub->add_option("--target-views", a->targetViews,
                  "Camera: stop when this many views cover enough of the image")
      ->capture_default_str();
  sub->add_flag("--k3", a->k3, "Estimate the third radial coefficient too (wide-angle lenses)");
  sub->add_flag("--fix-aspect", a->fixAspect, "Keep fx/fy = 1");
  sub->add_flag("--zero-tangent", a->zeroTangent, "Assume no tangential distortion");
  sub->add_option("--pattern", a->pattern,
                  "The printed target: charuco (the board `markers` prints) or chessboard (a "
                  "plain chessboard: --squares and --square-mm only)")
      ->capture_default_str();
  const CLI::Option* squares = sub->get_option("--squares");
  const CLI::Option* markerMm = sub->get_option("--marker-mm");
  const CLI::Option* dictionary = sub->get_option("--dictionary");
  return [a, squares, markerMm, dictionary] {
    a->squaresGiven = squares->count() > 0;
    a->markerOptionGiven = markerMm->count() > 0 || dictionary->count() > 0;
    return runCalibrate(*a);
  };
});

}  // namespace
}  // namespace ps::app
