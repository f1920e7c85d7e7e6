// Rigid marker sets as files: the committed planet board and tool cube layouts, the layout
// file's errors, the tool's stick read from it, the printed sheets read back, and the layouts
// carried by a live session's sidecar. (Their poses: test_tracking_board.cpp.)
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <memory>
#include <opencv2/imgproc.hpp>

#include "app/build_paths.hpp"
#include "core/input_error.hpp"
#include "error_of.hpp"
#include "fresh_dir.hpp"
#include "replay/session_timeline.hpp"
#include "tracking/detector.hpp"
#include "tracking/marker_layout.hpp"
#include "tracking/marker_sheet.hpp"
#include "tracking/tool_shape.hpp"

using namespace ps;
using testkit::errorOf;
using tracking::MarkerLayout;
using tracking::Pose;

namespace {

std::string parseError(const std::string& text) {
  return errorOf(
      [&] { tracking::parseMarkerLayout(nlohmann::json::parse(text), "bad-board.json"); });
}

// The sheet at 75 dpi with a camera's slight blur, through the AprilTag detector at full size.
std::vector<tracking::Detection> readSheet(const tracking::Sheet& sheet, double scale) {
  cv::Mat small;
  cv::resize(sheet.image, small, {}, scale, scale, cv::INTER_AREA);
  cv::GaussianBlur(small, small, {0, 0}, 0.6);
  tracking::DetectorConfig dc;
  dc.regions = false;
  dc.decimate = 1;
  return tracking::makeDetector(dc)->detect(small);
}

}  // namespace

TEST(TrackingBoard, CommittedLayoutsAreValid) {
  const MarkerLayout board =
      tracking::loadMarkerLayout(tracking::defaultBoardPath(app::sourceDir()));
  EXPECT_EQ(board.family, "tag36h11");
  EXPECT_GE(board.markers.size(), 4u);
  EXPECT_TRUE(board.planar());
  ASSERT_TRUE(board.planetCentre.has_value());
  EXPECT_GT(board.planetCentre->z(), 0.0);  // above the printed face
  const MarkerLayout tool =
      tracking::loadMarkerLayout(tracking::defaultToolLayoutPath(app::sourceDir()));
  EXPECT_FALSE(tool.planar());
  ASSERT_TRUE(tool.tip.has_value());
  // No id in both: the tracker tells board from tool by id alone.
  for (int id : tool.ids()) EXPECT_EQ(board.find(id), nullptr) << id;
  // Every marker's frame is right-handed, with z out of the printed face.
  for (const auto* l : {&board, &tool})
    for (const auto& m : l->markers) {
      const Pose p = m.inBody();
      EXPECT_NEAR(p.R.determinant(), 1.0, 1e-12);
      EXPECT_NEAR((p.R.transpose() * p.R - Eigen::Matrix3d::Identity()).norm(), 0.0, 1e-12);
    }
  // The cube's faces point away from its centre.
  for (const auto& m : tool.markers) EXPECT_GT(m.inBody().R.col(2).dot(m.inBody().t), 0.0);
}

TEST(TrackingBoard, LayoutRoundTripsThroughJson) {
  const MarkerLayout a =
      tracking::loadMarkerLayout(tracking::defaultToolLayoutPath(app::sourceDir()));
  const MarkerLayout b = tracking::parseMarkerLayout(tracking::toJson(a), "again");
  ASSERT_EQ(a.markers.size(), b.markers.size());
  for (std::size_t i = 0; i < a.markers.size(); ++i) {
    EXPECT_EQ(a.markers[i].id, b.markers[i].id);
    for (std::size_t k = 0; k < 4; ++k) EXPECT_EQ(a.markers[i].corners[k], b.markers[i].corners[k]);
  }
  EXPECT_EQ(*a.tip, *b.tip);
  // Millimetres read as metres.
  const MarkerLayout mm = tracking::parseMarkerLayout(
      nlohmann::json::parse(R"({"family": "tag36h11", "units": "mm", "markers": [{"id": 3,
        "corners": [[-20, 20, 0], [20, 20, 0], [20, -20, 0], [-20, -20, 0]]}]})"),
      "mm.json");
  EXPECT_DOUBLE_EQ(mm.markers[0].edge(), 0.04);
}

TEST(TrackingBoard, MalformedLayoutsAreRefusedNamingFileAndEntry) {
  const std::string square =
      R"([[-0.02, 0.02, 0], [0.02, 0.02, 0], [0.02, -0.02, 0], [-0.02, -0.02, 0]])";
  auto one = [&](const std::string& extra, const std::string& corners, int id = 3) {
    return R"({"family": "tag36h11", "units": "m", )" + extra + R"("markers": [{"id": )" +
           std::to_string(id) + R"(, "corners": )" + corners + "}]}";
  };
  EXPECT_EQ(parseError(one("", square)), "");
  auto expectError = [](const std::string& msg, const std::string& part) {
    EXPECT_EQ(msg.rfind("bad-board.json: ", 0), 0u) << msg;
    EXPECT_NE(msg.find(part), std::string::npos) << msg << "\nexpected: " << part;
  };
  expectError(parseError(R"({"family": "tag36h11", "markers": [{"id": 3, "corners": )" + square +
                         R"(}, {"id": 3, "corners": )" + square + "}]}"),
              "markers[1] (id 3): id 3 appears twice");
  expectError(
      parseError(
          one("", R"([[-0.02, 0.02, 0], [0.03, 0.02, 0], [0.02, -0.02, 0], [-0.02, -0.02, 0]])")),
      "markers[0] (id 3): not a square");
  expectError(
      parseError(one(
          "", R"([[-0.02, 0.02, 0], [0.02, 0.02, 0], [0.02, -0.02, 0.01], [-0.02, -0.02, 0]])")),
      "markers[0] (id 3)");
  expectError(parseError(one("", R"([[0, 0, 0], [0, 0, 0], [0, 0, 0], [0, 0, 0]])")),
              "markers[0] (id 3): edge 0 m is not > 0.1 mm");
  expectError(parseError(one("", square, 587)), "id outside tag36h11 (0..586)");
  expectError(parseError(one(R"("units": "inch", )", square)), "units \"inch\"");
  expectError(parseError(R"({"family": "tag99h1", "markers": []})"), "family: ");
  expectError(parseError(R"({"family": "tag36h11", "markers": []})"), "no \"markers\" array");
  expectError(parseError(one("", R"([[0, 0, 0], [1, 0]])")), "\"corners\" is not four");
  expectError(parseError(one(R"("planet_centre": [0, 0], )", square)), "planet_centre is not");
  const auto dir = testkit::freshDir("board_layout");
  std::ofstream(dir / "broken.json") << "{\"family\": ";
  const std::string msg = errorOf([&] { tracking::loadMarkerLayout(dir / "broken.json"); });
  EXPECT_NE(msg.find((dir / "broken.json").string() + ": not JSON"), std::string::npos) << msg;
  const std::string missing = errorOf([&] { tracking::loadMarkerLayout(dir / "absent.json"); });
  EXPECT_NE(missing.find("absent.json: cannot open"), std::string::npos) << missing;
}

// The tool's stick in its layout file: the committed cube's radii, the default, millimetres,
// and every bad value refused naming the file; the tool's shape follows from it.
TEST(TrackingBoard, ToolStickRadiusIsReadDefaultedAndRefused) {
  const MarkerLayout cube =
      tracking::loadMarkerLayout(tracking::defaultToolLayoutPath(app::sourceDir()));
  ASSERT_TRUE(cube.stickRadius && cube.stickTipRadius);
  EXPECT_DOUBLE_EQ(cube.stickBaseRadius(), 0.005);
  EXPECT_DOUBLE_EQ(cube.stickEndRadius(), 0.002);
  const MarkerLayout again = tracking::parseMarkerLayout(tracking::toJson(cube), "again");
  EXPECT_EQ(again.stickRadius, cube.stickRadius);
  EXPECT_EQ(again.stickTipRadius, cube.stickTipRadius);
  const std::string marker =
      R"("markers": [{"id": 3, "corners": [[-20, 20, 0], [20, 20, 0], [20, -20, 0], [-20, -20, 0]]}])";
  auto layout = [&](const std::string& extra) {
    return R"({"family": "tag36h11", "units": "mm", )" + extra + marker + "}";
  };
  const MarkerLayout plain =
      tracking::parseMarkerLayout(nlohmann::json::parse(layout(R"("tip": [0, -90, 0], )")), "t");
  EXPECT_FALSE(plain.stickRadius.has_value());
  EXPECT_DOUBLE_EQ(plain.stickBaseRadius(), tracking::kDefaultStickRadius);
  EXPECT_DOUBLE_EQ(plain.stickEndRadius(), tracking::kDefaultStickRadius);
  const MarkerLayout mm = tracking::parseMarkerLayout(
      nlohmann::json::parse(layout(R"("tip": [0, -90, 0], "stick_radius": 3, )")), "t");
  EXPECT_DOUBLE_EQ(mm.stickBaseRadius(), 0.003);
  EXPECT_DOUBLE_EQ(mm.stickEndRadius(), 0.003);  // the tip's radius defaults to the stick's
  auto refused = [&](const std::string& extra, const std::string& part) {
    const std::string msg = parseError(layout(extra));
    EXPECT_EQ(msg.rfind("bad-board.json: ", 0), 0u) << msg;
    EXPECT_NE(msg.find(part), std::string::npos) << msg << "\nexpected: " << part;
  };
  refused(R"("tip": [0, -90, 0], "stick_radius": -1, )",
          "\"stick_radius\" -0.001 m is not in (0, ");
  refused(R"("tip": [0, -90, 0], "stick_radius": 0, )", "\"stick_radius\" 0 m is not in");
  refused(R"("tip": [0, -90, 0], "stick_radius": 500, )", "\"stick_radius\" 0.5 m is not in");
  refused(R"("tip": [0, -90, 0], "stick_radius": "thin", )", "\"stick_radius\" is not a number");
  refused(R"("tip": [0, -90, 0], "stick_tip_radius": 1e300, )", "stick_tip_radius");
  refused(R"("stick_radius": 3, )", "\"stick_radius\" without a \"tip\"");

  // The cube's shape: the 50 mm box its 40 mm markers' quiet zones make, the stick from the
  // face under the tip down to the tip.
  const tracking::ToolShape shape = tracking::toolShape(cube, *cube.tip);
  EXPECT_LT((shape.boxCentre).norm(), 1e-12);
  EXPECT_LT((shape.boxHalf - Eigen::Vector3d::Constant(0.025)).norm(), 1e-12);
  EXPECT_LT((shape.stickBase - Eigen::Vector3d(0, -0.025, 0)).norm(), 1e-12);
  EXPECT_EQ(shape.tip, *cube.tip);
  // Every triangle's points lie on the box's surface or on the cone's.
  const auto triangles = tracking::toolTriangles(shape, Pose{}, 1.0, 16);
  EXPECT_EQ(triangles.size(), std::size_t(3 * (12 + 4 * 16)));
  for (const auto& p : triangles) {
    const Eigen::Vector3d q = (p - shape.boxCentre).cwiseAbs();
    const bool onBox = q.maxCoeff() < 0.025 + 1e-12 && q.maxCoeff() > 0.025 - 1e-12;
    const double along = (p - shape.stickBase).dot(Eigen::Vector3d(0, -1, 0)) / 0.08;
    const double off = std::hypot(p.x(), p.z());
    const bool onCone =
        along > -1e-12 && along < 1 + 1e-12 && off < 0.005 + (0.002 - 0.005) * along + 1e-12;
    EXPECT_TRUE(onBox || onCone) << p.transpose();
  }
}

// The printed board reads back with every id at its place: marker centres as far apart on the
// paper (px / dpi) as in the layout, corners where the sheet says.
TEST(TrackingBoard, BoardAndCubeSheetsReadBackAsTheirLayouts) {
  const MarkerLayout board =
      tracking::loadMarkerLayout(tracking::defaultBoardPath(app::sourceDir()));
  const MarkerLayout cube =
      tracking::loadMarkerLayout(tracking::defaultToolLayoutPath(app::sourceDir()));
  const double scale = 0.25;  // 75 dpi
  for (const auto& paper : {tracking::paperA4(), tracking::paperLetter()}) {
    SCOPED_TRACE(paper.name);
    for (const auto* layout : {&board, &cube}) {
      const auto sheet = layout == &board ? tracking::renderBoardSheet(*layout, paper, 300)
                                          : tracking::renderCubeNetSheet(*layout, paper, 300);
      const auto found = readSheet(sheet, scale);
      ASSERT_EQ(found.size(), layout->markers.size()) << sheet.title;
      ASSERT_EQ(sheet.markers.size(), layout->markers.size());
      for (const auto& [id, corners] : sheet.markers) {
        const auto it = std::find_if(found.begin(), found.end(),
                                     [id = id](const auto& d) { return d.id == id; });
        ASSERT_NE(it, found.end()) << "id " << id << " not read back";
        for (std::size_t k = 0; k < 4; ++k) {
          const cv::Point2d expected =
              (corners[k] + cv::Point2d(0.5, 0.5)) * scale - cv::Point2d(0.5, 0.5);
          EXPECT_LT(cv::norm(it->corners[k] - expected), 0.35) << "id " << id << " corner " << k;
        }
      }
    }
    // On the board, the distance between any two markers' centres is the layout's.
    const auto sheet = tracking::renderBoardSheet(board, paper, 300);
    auto centreOf = [](const std::array<cv::Point2d, 4>& c) {
      return 0.25 * (c[0] + c[1] + c[2] + c[3]);
    };
    for (std::size_t a = 0; a < board.markers.size(); ++a)
      for (std::size_t b = a + 1; b < board.markers.size(); ++b) {
        const double paperMm =
            cv::norm(centreOf(sheet.markers[a].second) - centreOf(sheet.markers[b].second)) * 25.4 /
            300;
        const double layoutMm =
            1e3 * (board.markers[a].inBody().t - board.markers[b].inBody().t).norm();
        EXPECT_NEAR(paperMm, layoutMm, 25.4 / 300)
            << board.markers[a].id << "-" << board.markers[b].id;
      }
  }
  // A layout a flat sheet cannot hold is refused, naming it.
  const std::string msg =
      errorOf([&] { tracking::renderBoardSheet(cube, tracking::paperA4(), 300); });
  EXPECT_NE(msg.find("tool-cube.json: cannot print as a board"), std::string::npos) << msg;
}

// A live session tracked with the board and the cube records both layouts in its sidecar, and a
// replay of it takes them from there; a sidecar with a broken layout is refused naming its line.
TEST(TrackingBoard, SessionSidecarCarriesTheLayouts) {
  replay::SessionStart start;
  start.gridSide = 129;
  start.radius = 6.4e6;
  start.calibrationFile = "calib/synthetic-640x480.yml";
  start.imageSize = {640, 480};
  start.K = {600, 0, 319.5, 0, 600, 239.5, 0, 0, 1};
  start.distortion = {0, 0, 0, 0, 0};
  start.family = "tag36h11";
  start.board = std::make_shared<const MarkerLayout>(
      tracking::loadMarkerLayout(tracking::defaultBoardPath(app::sourceDir())));
  start.toolLayout = std::make_shared<const MarkerLayout>(
      tracking::loadMarkerLayout(tracking::defaultToolLayoutPath(app::sourceDir())));
  start.tipOffset = *start.toolLayout->tip;
  const auto dir = testkit::freshDir("board_sidecar");
  const auto path = dir / "rec.mkv.session.jsonl";
  {
    replay::TimelineWriter w;
    w.open(path, start, replay::SessionSettings{});
    w.close();
  }
  const replay::SessionTimeline t = replay::readSessionTimeline(path);
  ASSERT_TRUE(t.start.board && t.start.toolLayout);
  EXPECT_EQ(t.start.board->ids(), start.board->ids());
  EXPECT_EQ(t.start.toolLayout->ids(), start.toolLayout->ids());
  replay::ReplayOptions o;
  t.start.applyTo(o);
  ASSERT_TRUE(o.scene.planet.layout && o.scene.tool.layout);
  EXPECT_TRUE(o.scene.planet.holdWhileStill);
  EXPECT_EQ(*o.scene.planet.layout->planetCentre, *start.board->planetCentre);
  EXPECT_EQ(o.scene.tipOffset, *start.toolLayout->tip);
  // An old sidecar (no layouts) replays with the single markers.
  replay::SessionStart old = start;
  old.board = old.toolLayout = nullptr;
  {
    replay::TimelineWriter w;
    w.open(dir / "old.session.jsonl", old, replay::SessionSettings{});
    w.close();
  }
  replay::ReplayOptions single;
  single.scene.useBoard(start.board);
  replay::readSessionTimeline(dir / "old.session.jsonl").start.applyTo(single);
  EXPECT_EQ(single.scene.planet.layout, nullptr);
  EXPECT_FALSE(single.scene.planet.holdWhileStill);
  // A damaged layout in the header.
  std::ifstream in(path);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const auto at = text.find("\"id\":10");
  ASSERT_NE(at, std::string::npos);
  text.replace(at, 7, "\"id\":11");
  const std::string msg = errorOf([&] { replay::parseSessionTimeline(text, path); });
  EXPECT_NE(
      msg.find("rec.mkv.session.jsonl:1: markers.board: markers[1] (id 11): id 11 appears twice"),
      std::string::npos)
      << msg;
}
