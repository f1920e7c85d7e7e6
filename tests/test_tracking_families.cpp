// Boards and tools of any family (issue 42 part 3): a board of one family beside a tool of
// another is tracked (ids clash within a family only, a detection is known by family and id),
// every family the layouts name is detected without --family, and the replay's stepper does it
// from the layouts alone.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <memory>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "app/build_paths.hpp"
#include "core/input_error.hpp"
#include "error_of.hpp"
#include "fresh_dir.hpp"
#include "median.hpp"
#include "replay/replay.hpp"
#include "test_terrains.hpp"
#include "tracking/detector.hpp"
#include "tracking/marker_family.hpp"
#include "tracking/marker_layout.hpp"
#include "tracking/marker_sheet.hpp"
#include "tracking/synth.hpp"
#include "tracking/tracker.hpp"

using namespace ps;
using testkit::errorOf;
using tracking::MarkerLayout;

namespace {

// The committed board in another family, its ids from `firstId` on (the same geometry).
std::shared_ptr<const MarkerLayout> boardOf(const std::string& family, int firstId) {
  MarkerLayout l = tracking::loadMarkerLayout(tracking::defaultBoardPath(app::sourceDir()));
  l.family = family;
  for (std::size_t i = 0; i < l.markers.size(); ++i) l.markers[i].id = firstId + int(i);
  l.source = family + " board";
  return std::make_shared<const MarkerLayout>(l);
}

std::shared_ptr<const MarkerLayout> committedCube() {
  return std::make_shared<const MarkerLayout>(
      tracking::loadMarkerLayout(tracking::defaultToolLayoutPath(app::sourceDir())));
}

// The board sweep with an ArUco board holding ids 20..28 beside the tag36h11 cube (ids 20..24):
// the case that was refused as "both hold id 20".
// (Its frames at 0.6 m, 160..239, show both the board and the cube.)
tracking::SynthScript mixedSweep() {
  tracking::SynthScript s = tracking::builtinScene("board-sweep", app::sourceDir());
  s.board = boardOf("DICT_4X4_50", 20);
  s.toolLayout = committedCube();
  return s;
}
constexpr int kFirstFrame = 160;

using testkit::median;

}  // namespace

TEST(TrackingFamilies, IdsClashWithinOneFamilyOnly) {
  tracking::SceneConfig mixed;
  mixed.useBoard(boardOf("DICT_4X4_50", 20));
  mixed.useToolLayout(committedCube());
  EXPECT_NO_THROW(mixed.validate());
  tracking::SceneConfig same;
  same.useBoard(boardOf("tag36h11", 20));
  same.useToolLayout(committedCube());
  const std::string msg = errorOf([&] { same.validate(); });
  EXPECT_NE(msg.find("both hold id 20"), std::string::npos) << msg;
  // A detection is the tracker's by family and id.
  tracking::Detection d;
  d.id = 20;
  d.family = "DICT_4X4_50";
  EXPECT_TRUE(mixed.planet.owns(d));
  EXPECT_FALSE(mixed.tool.owns(d));
  d.family = "tag36h11";
  EXPECT_FALSE(mixed.planet.owns(d));
  EXPECT_TRUE(mixed.tool.owns(d));
  // One family given twice to one detector is refused.
  tracking::DetectorConfig a;
  const std::string twice = errorOf([&] { tracking::makeDetector(std::vector{a, a}); });
  EXPECT_NE(twice.find("tag36h11 is given twice"), std::string::npos) << twice;
}

// Every frame's detections carry their family; the board's pose and the tool's tip follow the
// ground truth in the frames that show them, with both families' id 20..24 in view together.
TEST(TrackingFamilies, BoardAndToolOfTwoFamiliesTrackTogether) {
  const tracking::SynthRenderer r(mixedSweep());
  const auto& s = r.script();
  std::vector<tracking::DetectorConfig> families(2);
  families[0].family = s.board->family;
  families[0].ids = s.board->ids();
  families[0].sets = {s.board->ids()};
  families[1].family = s.toolLayout->family;
  families[1].ids = s.toolLayout->ids();
  families[1].sets = {s.toolLayout->ids()};
  auto detector = tracking::makeDetector(families);
  tracking::SceneConfig sc;
  sc.useBoard(s.board);
  sc.useToolLayout(s.toolLayout);
  tracking::SceneTracker tracker(sc);
  int planetVisible = 0, planetMeasured = 0, toolVisible = 0, toolMeasured = 0, sharedIds = 0;
  std::vector<double> centreErr, tipErr;
  for (int f = kFirstFrame; f < kFirstFrame + 80; ++f) {
    const auto truth = r.truth(f);
    const auto found = detector->detect(r.render(f));
    bool board20 = false, cube20 = false;
    for (const auto& d : found) {
      ASSERT_TRUE(d.family == "DICT_4X4_50" || d.family == "tag36h11") << d.family;
      const auto& layout = d.family == "DICT_4X4_50" ? *s.board : *s.toolLayout;
      EXPECT_NE(layout.find(d.id), nullptr) << d.family << " id " << d.id << " frame " << f;
      board20 |= d.id == 20 && d.family == "DICT_4X4_50";
      cube20 |= d.id == 20 && d.family == "tag36h11";
    }
    sharedIds += board20 && cube20 ? 1 : 0;
    const auto frame = tracker.update(found, s.camera, f, f / s.fps);
    if (truth.planetVisible) {
      ++planetVisible;
      if (frame.planet.measured) {
        ++planetMeasured;
        centreErr.push_back((frame.planetCentreCamera - truth.planetCentreCamera).norm());
      }
    }
    if (truth.toolVisible) {
      ++toolVisible;
      if (frame.tool.measured && frame.tipValid)
        ++toolMeasured, tipErr.push_back((frame.tipCamera - truth.tipCamera).norm());
    }
  }
  ASSERT_GE(planetVisible, 40);
  ASSERT_GE(toolVisible, 40);
  EXPECT_GE(sharedIds, 20) << "frames showing the board's id 20 and the cube's id 20 together";
  EXPECT_GE(planetMeasured, 0.95 * planetVisible);
  EXPECT_GE(toolMeasured, 0.9 * toolVisible);
  EXPECT_LT(median(centreErr), 0.003) << "board centre error (m)";
  EXPECT_LT(median(tipErr), 0.003) << "tool tip error (m)";
}

// The replay's stepper (live, replay, demo) detects each family its layouts name, whatever
// --family says (it is the single markers' family).
TEST(TrackingFamilies, StepperDetectsTheFamiliesTheLayoutsName) {
  const tracking::SynthRenderer r(mixedSweep());
  replay::ReplayOptions o;
  o.detector.family = "DICT_6X6_250";  // neither layout's
  o.scene.useBoard(r.script().board);
  o.scene.useToolLayout(r.script().toolLayout);
  terrain::Terrain planet = testkit::bumpyTerrain(5);
  replay::FrameStepper stepper(r.script().camera, planet, o);
  EXPECT_EQ(stepper.family(), "DICT_4X4_50, tag36h11");
  int both = 0;
  for (int f = kFirstFrame; f < kFirstFrame + 20; ++f) {
    const auto out = stepper.step(r.render(f), f, f / r.script().fps);
    both += out.scene.planet.measured && out.scene.tool.measured ? 1 : 0;
  }
  EXPECT_GE(both, 15);
  // A board and a tool of one family holding one id are still refused.
  replay::ReplayOptions clash = o;
  clash.scene.useBoard(boardOf("tag36h11", 20));
  const std::string msg = errorOf([&] { replay::FrameStepper(r.script().camera, planet, clash); });
  EXPECT_NE(msg.find("both hold id 20"), std::string::npos) << msg;
}

// `planetsculpt markers` prints a board and a tool in families and sizes of the user's choice,
// with their layout files beside the sheets: the files load, hold the family and size asked
// for, and every marker they name is read back from the printed sheet in that family, at the
// place the sheet says.
TEST(TrackingFamilies, MarkersPrintsABoardAndAToolOfAnyFamilyWithTheirLayouts) {
  const std::filesystem::path exe = app::commandPath();
  if (!std::filesystem::exists(exe)) GTEST_SKIP() << "no " << exe << " in this build";
  const auto dir = testkit::freshDir("markers_families");
  const std::string command = "'" + exe.string() + "' markers --out '" + dir.string() +
                              "' --paper a4 --format png --board-family DICT_4X4_50 "
                              "--board-marker-mm 40 --tool-family tag25h9 "
                              "--tool-marker-mm 30 > '" +
                              (dir / "log.txt").string() + "' 2>&1";
  ASSERT_EQ(std::system(command.c_str()), 0) << command;
  const MarkerLayout board = tracking::loadMarkerLayout(dir / "planet-board.json");
  const MarkerLayout tool = tracking::loadMarkerLayout(dir / "tool-cube.json");
  const MarkerLayout committedBoard =
      tracking::loadMarkerLayout(tracking::defaultBoardPath(app::sourceDir()));
  const MarkerLayout committedTool = *committedCube();
  EXPECT_EQ(board.family, "DICT_4X4_50");
  EXPECT_EQ(tool.family, "tag25h9");
  EXPECT_EQ(board.ids(), committedBoard.ids());
  EXPECT_EQ(tool.ids(), committedTool.ids());
  for (const auto& m : board.markers) EXPECT_NEAR(m.edge(), 0.040, 1e-9) << m.id;
  for (const auto& m : tool.markers) EXPECT_NEAR(m.edge(), 0.030, 1e-9) << m.id;
  // The board scales about its origin; the cube's faces move out to hold the markers with the
  // new family's quiet zone, the tip with them (the sheet's cube-net check holds them too).
  ASSERT_TRUE(tool.tip && board.planetCentre);
  EXPECT_NEAR(board.planetCentre->z(), committedBoard.planetCentre->z() * 0.8, 1e-9);
  const double faces = tool.find(20)->inBody().t.norm() / committedTool.find(20)->inBody().t.norm();
  const auto info = tracking::familyInfo("tag25h9");
  EXPECT_NEAR(tool.find(20)->inBody().t.norm(), 0.030 * info.totalCells / info.edgeCells / 2, 1e-9);
  EXPECT_NEAR(tool.tip->y(), committedTool.tip->y() * faces, 1e-8);  // files hold nanometres
  // What `live --board FILE --tool-layout FILE` is given.
  replay::ReplayOptions o;
  o.scene.useBoard(std::make_shared<const MarkerLayout>(board));
  o.scene.useToolLayout(std::make_shared<const MarkerLayout>(tool));
  EXPECT_NO_THROW(o.validate());
  // The printed sheets, at 150 dpi with a slight blur, read in their layouts' families.
  for (const auto& [file, layout] :
       {std::pair{"planet-board-a4.png", &board}, std::pair{"tool-cube-a4.png", &tool}}) {
    const cv::Mat sheet = cv::imread((dir / file).string(), cv::IMREAD_GRAYSCALE);
    ASSERT_FALSE(sheet.empty()) << file;
    cv::Mat small;
    cv::resize(sheet, small, {}, 0.5, 0.5, cv::INTER_AREA);
    cv::GaussianBlur(small, small, {0, 0}, 0.6);
    tracking::DetectorConfig dc;
    dc.family = layout->family;
    dc.regions = false;
    dc.decimate = 1;
    const auto found = tracking::makeDetector(dc)->detect(small);
    std::vector<int> ids;
    for (const auto& d : found) ids.push_back(d.id);
    EXPECT_EQ(ids, layout->ids()) << file;
    // The same sheet drawn in memory puts each marker where it was found.
    const auto drawn = layout == &board
                           ? tracking::renderBoardSheet(board, tracking::paperA4(), 300)
                           : tracking::renderCubeNetSheet(tool, tracking::paperA4(), 300);
    for (const auto& d : found)
      for (const auto& m : drawn.markers) {
        if (m.first != d.id) continue;
        const cv::Point2d expected =
            (m.second[0] + cv::Point2d(0.5, 0.5)) * 0.5 - cv::Point2d(0.5, 0.5);
        // (aruco's contour refinement sits about half a pixel inside: test_tracking_markers.cpp)
        EXPECT_LT(cv::norm(d.corners[0] - expected), 1.5) << file << " id " << d.id;
      }
  }
  // The same run again leaves the layouts as they are; a family too small for the ids, or the
  // board and the tool in one family sharing an id, is refused.
  auto fails = [&](const std::string& options, const std::string& message) {
    const std::string c = "'" + exe.string() + "' markers --out '" + (dir / "bad").string() +
                          "' --paper a4 --format png " + options + " > '" +
                          (dir / "bad.txt").string() + "' 2>&1";
    EXPECT_NE(std::system(c.c_str()), 0) << c;
    std::ifstream in(dir / "bad.txt");
    const std::string log((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    EXPECT_NE(log.find(message), std::string::npos) << options << "\n" << log;
  };
  { std::ofstream(dir / "board20.json") << tracking::layoutFileText(*boardOf("tag36h11", 20)); }
  fails("--family DICT_4X4_50 --board '" + (dir / "board20.json").string() + "'",
        "both hold id 20");
  // A family that does not hold the layout's ids is refused naming the layout.
  const std::string msg =
      errorOf([&] { tracking::resizedLayout(*boardOf("tag36h11", 40), "tag16h5", 0); });
  EXPECT_NE(msg.find("tag36h11 board"), std::string::npos) << msg;
  EXPECT_NE(msg.find("tag16h5"), std::string::npos) << msg;
  // Made again into the same folder, the layouts are left as they are.
  const auto before = std::filesystem::last_write_time(dir / "planet-board.json");
  ASSERT_EQ(std::system(command.c_str()), 0) << command;
  EXPECT_EQ(std::filesystem::last_write_time(dir / "planet-board.json"), before);
}

namespace {

// Where a cube face's centre lies in the printed net, in faces from the front (+z) face, and
// whether its marker is printed turned (marker_sheet.hpp: a cross, the top over the front over
// the bottom over the back, -x left and +x right of the front).
struct NetPlace {
  cv::Point2d offset;
  bool turned = false;
};
NetPlace netPlace(const Eigen::Vector3d& normal) {
  const std::pair<Eigen::Vector3d, NetPlace> places[] = {
      {Eigen::Vector3d::UnitY(), {{0, -1}, false}},  {Eigen::Vector3d::UnitZ(), {{0, 0}, false}},
      {-Eigen::Vector3d::UnitY(), {{0, 1}, false}},  {-Eigen::Vector3d::UnitZ(), {{0, 2}, true}},
      {-Eigen::Vector3d::UnitX(), {{-1, 0}, false}}, {Eigen::Vector3d::UnitX(), {{1, 0}, false}}};
  for (const auto& p : places)
    if ((p.first - normal).norm() < 1e-9) return p.second;
  ADD_FAILURE() << "no face of the net has the normal " << normal.transpose();
  return {};
}

// Each marker of a sheet as read back: its centre and its x axis (TL to TR) on the paper, mm.
struct ReadMarker {
  int id = -1;
  cv::Point2d centreMm, xAxisMm;
};

// A sheet's PNG as a camera 150 dpi away would see it (half size, a slight blur), through the
// family's own detector; positions back in millimetres of the 300-dpi page.
std::vector<ReadMarker> readBack(const std::filesystem::path& png, const std::string& family) {
  const cv::Mat sheet = cv::imread(png.string(), cv::IMREAD_GRAYSCALE);
  if (sheet.empty()) ADD_FAILURE() << "cannot read " << png;
  if (sheet.empty()) return {};
  constexpr double kScale = 0.5, kMmPerPx = 25.4 / 300;
  cv::Mat small;
  cv::resize(sheet, small, {}, kScale, kScale, cv::INTER_AREA);
  cv::GaussianBlur(small, small, {0, 0}, 0.6);
  tracking::DetectorConfig dc;
  dc.family = family;
  dc.regions = false;
  dc.decimate = 1;
  std::vector<ReadMarker> out;
  for (const auto& d : tracking::makeDetector(dc)->detect(small)) {
    auto page = [&](const cv::Point2d& p) {
      return ((p + cv::Point2d(0.5, 0.5)) / kScale - cv::Point2d(0.5, 0.5)) * kMmPerPx;
    };
    ReadMarker m;
    m.id = d.id;
    for (const auto& c : d.corners) m.centreMm += 0.25 * page(c);
    m.xAxisMm =
        0.5 * (page(d.corners[1]) + page(d.corners[2]) - page(d.corners[0]) - page(d.corners[3]));
    out.push_back(m);
  }
  std::sort(out.begin(), out.end(), [](const auto& a, const auto& b) { return a.id < b.id; });
  return out;
}

// The markers read back against where the layout puts them on the paper (`expected`, mm, up to
// one shift: where the sheet places the drawing), their x axes (`xAxis`, a unit vector on the
// paper) and edges: the worst centre error after the shift, mm.
double worstCentreError(const std::vector<ReadMarker>& found, const MarkerLayout& layout,
                        const std::function<cv::Point2d(const tracking::LayoutMarker&)>& expected,
                        const std::function<cv::Point2d(const tracking::LayoutMarker&)>& xAxis,
                        const std::string& what) {
  std::vector<int> ids;
  for (const auto& m : found) ids.push_back(m.id);
  EXPECT_EQ(ids, layout.ids()) << what << ": every marker read back, nothing else";
  if (ids != layout.ids()) return 1e9;
  cv::Point2d shift;
  for (const auto& m : found)
    shift += (m.centreMm - expected(*layout.find(m.id))) / double(found.size());
  double worst = 0;
  for (const auto& m : found) {
    const auto& l = *layout.find(m.id);
    worst = std::max(worst, cv::norm(m.centreMm - expected(l) - shift));
    // (aruco's contour refinement puts corners up to a pixel inside: 0.33 mm short on the 30 mm
    // DICT_5X5_100 faces at 150 dpi)
    EXPECT_NEAR(cv::norm(m.xAxisMm), 1e3 * l.edge(), 0.45) << what << " id " << m.id << ": edge";
    const cv::Point2d dir = m.xAxisMm / cv::norm(m.xAxisMm);
    EXPECT_GT(dir.dot(xAxis(l)), std::cos(0.5 * CV_PI / 180))
        << what << " id " << m.id << ": x axis " << dir;
  }
  return worst;
}

}  // namespace

// What `planetsculpt markers` prints in any family is read back from its own sheet: for an
// AprilTag family and OpenCV dictionaries of 4x4, 5x5, 6x6 and AprilTag 36h11 bits, the board's and
// the cube net's PNGs give every id of their layout files (nothing else), each marker's centre
// where the layout puts it on the paper (one shift for the whole sheet, the scale the sheet's
// 300 dpi), its edge the layout's and its x axis the right way. Until the net's fold lines were
// dashed, cubes of 8 or more cells across (DICT_6X6_250, DICT_APRILTAG_36h11), and a 30 mm
// DICT_5X5_100 one, read back nothing in OpenCV's detector (docs/TRACKING.md).
TEST(TrackingFamilies, BoardAndCubeOfEveryFamilyReadBackFromTheirSheets) {
  const std::filesystem::path exe = app::commandPath();
  if (!std::filesystem::exists(exe)) GTEST_SKIP() << "no " << exe << " in this build";
  const auto root = testkit::freshDir("markers_read_back");
  // The tool cube's marker edge: the layout's 40 mm, and the 30 mm DICT_5X5_100 cube that read
  // back nothing at 150 dpi before.
  const std::pair<std::string, std::string> cases[] = {{"tag36h11", "40"},
                                                       {"DICT_4X4_50", "40"},
                                                       {"DICT_5X5_100", "30"},
                                                       {"DICT_6X6_250", "40"},
                                                       {"DICT_APRILTAG_36h11", "40"}};
  for (const auto& printed : cases) {
    const std::string &family = printed.first, &toolMm = printed.second;
    SCOPED_TRACE(family);
    const auto dir = root / family;
    // 35 mm board markers: the 4x4 dictionary's quiet zone (1 cell of 6) makes the 50 mm board
    // too wide for A4.
    const std::string command = "'" + exe.string() + "' markers --out '" + dir.string() +
                                "' --paper a4 --format png --board-family " + family +
                                " --board-marker-mm 35 --tool-family " + family +
                                " --tool-marker-mm " + toolMm + " > '" +
                                (root / (family + ".log")).string() + "' 2>&1";
    ASSERT_EQ(std::system(command.c_str()), 0) << command;
    const MarkerLayout board = tracking::loadMarkerLayout(dir / "planet-board.json");
    const MarkerLayout cube = tracking::loadMarkerLayout(dir / "tool-cube.json");
    ASSERT_EQ(board.family, family);
    ASSERT_EQ(cube.family, family);
    // The board: x along the paper's width, y up the paper.
    const double boardError = worstCentreError(
        readBack(dir / "planet-board-a4.png", family), board,
        [](const tracking::LayoutMarker& m) {
          const Eigen::Vector3d c = m.inBody().t;
          return cv::Point2d(1e3 * c.x(), -1e3 * c.y());
        },
        [](const tracking::LayoutMarker&) { return cv::Point2d(1, 0); }, "board");
    EXPECT_LT(boardError, 0.15) << "board";
    // The cube: each face at its place in the net, faces as wide as the cube.
    const double faceMm = 2e3 * cube.markers.front().inBody().t.norm();
    const double cubeError = worstCentreError(
        readBack(dir / "tool-cube-a4.png", family), cube,
        [&](const tracking::LayoutMarker& m) {
          return netPlace(m.inBody().R.col(2)).offset * faceMm;
        },
        [](const tracking::LayoutMarker& m) {
          return cv::Point2d(netPlace(m.inBody().R.col(2)).turned ? -1 : 1, 0);
        },
        "cube");
    EXPECT_LT(cubeError, 0.15) << "cube";
    std::cerr << family << ": worst marker centre off its layout place by " << boardError
              << " mm (board), " << cubeError << " mm (cube)\n";
  }
}
