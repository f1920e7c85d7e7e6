// The live session's recording (session/frame_recorder.hpp) and the panel's export
// (session/planet_export.hpp), without a window.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "core/input_error.hpp"
#include "fresh_dir.hpp"
#include "session/frame_recorder.hpp"
#include "session/planet_export.hpp"
#include "test_terrains.hpp"
#include "tracking/video.hpp"

using namespace ps;
namespace fs = std::filesystem;

namespace {

// Frames a codec cannot cheat on: noise, a moving gradient, a flat field, saturated pixels.
std::vector<cv::Mat> syntheticFrames(int n, bool colour) {
  std::vector<cv::Mat> frames;
  cv::RNG rng(7);
  for (int i = 0; i < n; ++i) {
    cv::Mat f(48, 64, colour ? CV_8UC3 : CV_8UC1);
    rng.fill(f, cv::RNG::UNIFORM, 0, 256);
    f.rowRange(0, 8).setTo(cv::Scalar::all(i % 2 ? 255 : 0));
    for (int x = 0; x < 64; ++x) f.col(x).rowRange(8, 16).setTo(cv::Scalar::all((x * 4 + i) % 256));
    frames.push_back(f);
  }
  return frames;
}

}  // namespace

TEST(FrameRecorder, RecordedFramesReadBackPixelIdentical) {
  const fs::path dir = testkit::freshDir("session_record");
  for (bool colour : {false, true}) {
    const auto frames = syntheticFrames(12, colour);
    session::FrameRecorder rec;
    EXPECT_FALSE(rec.recording());
    rec.write(frames[0]);  // not recording: nothing happens
    const fs::path file = dir / (colour ? "bgr.mkv" : "grey.mkv");
    rec.start(file, 25);
    EXPECT_TRUE(rec.recording());
    EXPECT_EQ(rec.path(), file);
    for (const cv::Mat& f : frames) rec.write(f);
    EXPECT_EQ(rec.frames(), 12);
    EXPECT_EQ(rec.stop(), 12);
    EXPECT_FALSE(rec.recording());

    tracking::FrameSource src(file);
    EXPECT_EQ(src.size(), frames[0].size());
    EXPECT_DOUBLE_EQ(src.fps(), 25);
    cv::Mat got;
    int n = 0;
    while (src.read(got)) {
      ASSERT_LT(n, 12);
      cv::Mat want = frames[std::size_t(n)];
      if (got.channels() != want.channels()) {  // a decoder may hand grey video back as BGR
        ASSERT_FALSE(colour);
        ASSERT_EQ(got.channels(), 3);
        std::vector<cv::Mat> planes;
        cv::split(got, planes);
        for (const cv::Mat& p : planes)
          EXPECT_EQ(cv::norm(p, want, cv::NORM_INF), 0) << "frame " << n << " (grey)";
      } else {
        EXPECT_EQ(cv::norm(got, want, cv::NORM_INF), 0) << "frame " << n;
      }
      ++n;
    }
    EXPECT_EQ(n, 12);
  }
}

TEST(FrameRecorder, RefusesAFrameOfAnotherSizeAndStops) {
  const fs::path dir = testkit::freshDir("session_record_bad");
  session::FrameRecorder rec;
  rec.start(dir / "a.mkv", 30);
  rec.write(cv::Mat(48, 64, CV_8UC3, cv::Scalar(1, 2, 3)));
  EXPECT_ANY_THROW(rec.write(cv::Mat(40, 64, CV_8UC3, cv::Scalar(1, 2, 3))));
  EXPECT_FALSE(rec.recording());
  EXPECT_EQ(session::nextRecordingPath(dir), dir / "recording-001.mkv");
  std::ofstream(dir / "recording-001.mkv") << "x";
  EXPECT_EQ(session::nextRecordingPath(dir), dir / "recording-002.mkv");
}

TEST(PlanetExport, WritesHeightmapSidecarAndMeshUnderTheNextFreeName) {
  const fs::path dir = testkit::freshDir("session_export") / "exports";
  const auto planet = testkit::bumpyTerrain(7, 3, 4000.0);
  const auto a = session::exportPlanet(planet, dir);
  EXPECT_EQ(a.heightmap, dir / "planet-001.png");
  EXPECT_EQ(a.sidecar, dir / "planet-001.png.json");
  EXPECT_EQ(a.mesh, dir / "planet-001.glb");
  EXPECT_EQ(a.height, 128);  // min(m, 2048)
  EXPECT_EQ(a.width, 256);
  EXPECT_GT(a.triangles, 0u);
  EXPECT_GT(a.meshErrorM, 0);
  // The PNG is 16-bit, the size the summary says; the sidecar is JSON naming the projection.
  const cv::Mat png = cv::imread(a.heightmap.string(), cv::IMREAD_UNCHANGED);
  ASSERT_FALSE(png.empty());
  EXPECT_EQ(png.depth(), CV_16U);
  EXPECT_EQ(png.cols, 256);
  EXPECT_EQ(png.rows, 128);
  std::ifstream sc(a.sidecar);
  const auto j = nlohmann::json::parse(sc);
  EXPECT_TRUE(j.is_object());
  // The GLB starts with its magic and says its own length.
  {
    std::ifstream g(a.mesh, std::ios::binary);
    char head[12];
    g.read(head, 12);
    ASSERT_TRUE(g);
    EXPECT_EQ(std::string(head, 4), "glTF");
    std::uint32_t length = 0;
    std::memcpy(&length, head + 8, 4);
    EXPECT_EQ(length, fs::file_size(a.mesh));
  }
  EXPECT_NE(a.describe().find(a.heightmap.string()), std::string::npos);
  // No temporary file is left behind; the next export takes the next name.
  const auto b = session::exportPlanet(planet, dir, {64, 50.0});
  EXPECT_EQ(b.heightmap, dir / "planet-002.png");
  EXPECT_EQ(b.height, 64);
  EXPECT_DOUBLE_EQ(b.meshErrorM, 50.0);
  int files = 0;
  for (const auto& e : fs::directory_iterator(dir)) {
    EXPECT_NE(e.path().filename().string()[0], '.') << e.path();
    ++files;
  }
  EXPECT_EQ(files, 6);
  // A name taken by any one of the three files is skipped.
  std::ofstream(dir / "planet-003.glb") << "x";
  EXPECT_EQ(session::nextExportStem(dir), "planet-004");
}

TEST(PlanetExport, InTheBackgroundFromACopyOfThePlanet) {
  const fs::path dir = testkit::freshDir("session_export_bg") / "exports";
  auto planet = testkit::bumpyTerrain(7, 3, 4000.0);
  const auto reference = session::exportPlanet(planet, dir / "ref");
  session::BackgroundExport job;
  EXPECT_FALSE(job.running());
  EXPECT_FALSE(job.poll().has_value());
  job.start(planet, dir);
  EXPECT_TRUE(job.running());
  EXPECT_THROW(job.start(planet, dir), core::InputError);  // one at a time
  // The live planet changes while the copy is exported.
  planet.mutableHeights()[planet.grid().index(5, 60)] += 1000.f;
  planet.commitEdit(terrain::VertexBox::point({5, 60}));
  const auto outcome = job.wait();
  ASSERT_TRUE(outcome.has_value());
  ASSERT_TRUE(outcome->result.has_value()) << outcome->error;
  EXPECT_FALSE(job.running());
  EXPECT_FALSE(job.poll().has_value());  // reported once
  // The same bytes as an export of the planet as it was when the export started.
  for (const auto& [a, b] : {std::pair{outcome->result->heightmap, reference.heightmap},
                             std::pair{outcome->result->mesh, reference.mesh}}) {
    std::ifstream fa(a, std::ios::binary), fb(b, std::ios::binary);
    const std::string sa((std::istreambuf_iterator<char>(fa)), {}),
        sb((std::istreambuf_iterator<char>(fb)), {});
    EXPECT_FALSE(sa.empty());
    EXPECT_TRUE(sa == sb) << a << " differs from " << b;
  }
  // A failure is an outcome with the error, not an exception in the app's loop.
  std::ofstream(dir.parent_path() / "file") << "x";
  job.start(planet, dir.parent_path() / "file" / "exports");
  const auto failed = job.wait();
  ASSERT_TRUE(failed.has_value());
  EXPECT_FALSE(failed->result.has_value());
  EXPECT_FALSE(failed->error.empty());
}
