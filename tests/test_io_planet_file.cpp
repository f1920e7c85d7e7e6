// Planet files: exact round trips, a clear error for every kind of bad file, and saves that
// survive being killed at random moments.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>
#include <zlib.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>

#include "core/chart_factory.hpp"
#include "core/cylinder_chart.hpp"
#include "core/flat_chart.hpp"
#include "core/input_error.hpp"
#include "core/torus_chart.hpp"
#include "fresh_dir.hpp"
#include "io/planet_file.hpp"
#include "test_terrains.hpp"

using namespace ps;
namespace fs = std::filesystem;

namespace {

using testkit::readAll;
using testkit::writeAll;

// Re-stamps the header CRC after a deliberate header edit, so the check under test is reached.
// zlib's CRC-32 (the format's checksum) over bytes [from, to) of b.
std::uint32_t crcOf(const std::vector<unsigned char>& b, std::size_t from, std::size_t to) {
  return std::uint32_t(::crc32(0, b.data() + from, uInt(to - from)));
}

void fixHeaderCrc(std::vector<unsigned char>& b) {
  const std::uint32_t c = crcOf(b, 0, 124);
  std::memcpy(b.data() + 124, &c, 4);
}

void fixBodyCrc(std::vector<unsigned char>& b) {
  const std::uint32_t c = crcOf(b, 128, b.size());
  std::memcpy(b.data() + 96, &c, 4);
  fixHeaderCrc(b);
}

// Expects parsePlanet to refuse `bytes` with a message naming the file and containing `what`.
void expectRefused(const std::vector<unsigned char>& bytes, const std::string& what) {
  const std::string name = "some/dir/world.planet";
  try {
    io::parsePlanet(bytes, name);
    ADD_FAILURE() << "accepted a bad file; expected: " << what;
  } catch (const core::InputError& e) {
    const std::string msg = e.what();
    EXPECT_EQ(msg.rfind(name + ": ", 0), 0u) << msg;
    EXPECT_NE(msg.find(what), std::string::npos)
        << "message: " << msg << "\nexpected to contain: " << what;
  }
}

std::vector<unsigned char> goodFile(int n = 5) {
  auto chart = testkit::earthChart(n);
  return io::encodePlanet(*chart, testkit::bumpyHeights(*chart, 3, 5000.0),
                          terrain::ErrorRule::kHybridExact,
                          {io::HeightEncoding::kFloat32, {{"note", "test"}}});
}

}  // namespace

TEST(IoPlanetFile, LatLongRoundTripIsBitExactOnDiskAndThroughLoad) {
  const fs::path dir = testkit::freshDir("io_roundtrip");
  const auto t = testkit::bumpyTerrain(6, 4, 9000.0, terrain::ErrorRule::kWedgie);
  io::PlanetSaveOptions opts;
  opts.metadata = {{"author", "test"}};
  io::savePlanet(t, dir / "a.planet", opts);
  const auto bytes = readAll(dir / "a.planet");
  EXPECT_EQ(bytes, io::encodePlanet(t.chart(), t.heights(), t.bounds().rule(), opts));
  const auto loaded = io::loadPlanet(dir / "a.planet");
  ASSERT_EQ(loaded->heights().size(), t.heights().size());
  EXPECT_EQ(
      std::memcmp(loaded->heights().data(), t.heights().data(), t.heights().size() * sizeof(float)),
      0);
  EXPECT_EQ(loaded->chart().name(), "latlong");
  EXPECT_EQ(loaded->chart().sphereRadius(), t.chart().sphereRadius());
  EXPECT_EQ(loaded->bounds().rule(), terrain::ErrorRule::kWedgie);
  EXPECT_EQ(loaded->bounds().errorCodes(), t.bounds().errorCodes());
  EXPECT_EQ(io::readPlanetFile(dir / "a.planet").metadata.at("author"), "test");
  // Saving what was loaded gives the same bytes.
  io::savePlanet(*loaded, dir / "b.planet", opts);
  EXPECT_EQ(readAll(dir / "b.planet"), bytes);
  fs::remove_all(dir);
}

TEST(IoPlanetFile, Uint16EncodingIsWithinHalfAStepAndKeepsSeamAndPoles) {
  auto chart = testkit::earthChart(6);
  const auto h = testkit::bumpyHeights(*chart, 8, 7000.0);
  const auto bytes = io::encodePlanet(*chart, h, terrain::ErrorRule::kHybridExact,
                                      {io::HeightEncoding::kUint16, {}});
  EXPECT_LT(bytes.size(), 128 + h.size() * 2 + 8);
  const io::PlanetData d = io::parsePlanet(bytes, "u16.planet");
  EXPECT_EQ(d.encoding, io::HeightEncoding::kUint16);
  const auto [lo, hi] = std::minmax_element(h.begin(), h.end());
  const double step = (double(*hi) - double(*lo)) / 65535.0;
  for (std::size_t i = 0; i < h.size(); ++i)
    ASSERT_LE(std::abs(double(d.heights[i]) - h[i]), 0.5 * step + 1e-3);
  EXPECT_NO_THROW(terrain::Terrain(d.chart, d.heights));
}

TEST(IoPlanetFile, FlatChartFieldsRoundTrip) {
  auto chart = std::make_shared<core::FlatChart>(core::GridSize(5), 30.0, 20.0);
  std::vector<float> h(chart->grid().count());
  for (std::size_t i = 0; i < h.size(); ++i) h[i] = float(std::sin(0.1 * double(i)) * 50.0);
  const auto bytes = io::encodePlanet(*chart, h, terrain::ErrorRule::kHybridExact);
  // A refusal here is a failure: flat heights are not limited by a planet radius.
  const io::PlanetData d = io::parsePlanet(bytes, "flat.planet");
  const auto* flat = dynamic_cast<const core::FlatChart*>(d.chart.get());
  ASSERT_NE(flat, nullptr);
  EXPECT_EQ(flat->dx(), 30.0);
  EXPECT_EQ(flat->dy(), 20.0);
  EXPECT_EQ(d.heights, h);
}

TEST(IoPlanetFile, OctahedralPlanetsRoundTripAsVersion2AndLatLongStaysVersion1) {
  for (const auto mapping :
       {core::OctahedralChart::Mapping::kEqualArea, core::OctahedralChart::Mapping::kCentral}) {
    const auto t = testkit::bumpyOctahedralTerrain(6, 5, 9000.0, mapping);
    const auto bytes = io::encodePlanet(t.chart(), t.heights(), t.bounds().rule());
    std::uint32_t version = 0;
    std::memcpy(&version, bytes.data() + 8, 4);
    EXPECT_EQ(version, 2u);
    EXPECT_EQ(std::string(reinterpret_cast<const char*>(bytes.data() + 16)), "octahedral");
    const io::PlanetData d = io::parsePlanet(bytes, "octa.planet");
    const auto* oct = dynamic_cast<const core::OctahedralChart*>(d.chart.get());
    ASSERT_NE(oct, nullptr);
    EXPECT_EQ(oct->mapping(), mapping);
    EXPECT_EQ(oct->sphereRadius(), t.chart().sphereRadius());
    EXPECT_EQ(oct->grid().side(), t.grid().side());
    EXPECT_EQ(std::memcmp(d.heights.data(), t.heights().data(), t.heights().size() * 4), 0);
    // The same planet through a save and a load: the same bytes again.
    EXPECT_EQ(io::encodePlanet(*d.chart, d.heights, d.rule), bytes);
  }
  std::uint32_t version = 0;
  const auto latlong = goodFile();
  std::memcpy(&version, latlong.data() + 8, 4);
  EXPECT_EQ(version, 1u) << "a planet version 1 holds must stay readable by older builds";
}

TEST(IoPlanetFile, OctahedralHeaderFieldsAndTwinsAreChecked) {
  const auto t = testkit::bumpyOctahedralTerrain(5, 2, 5000.0);
  const auto good = io::encodePlanet(t.chart(), t.heights(), t.bounds().rule());
  auto edit = [&](std::size_t off, const void* value, std::size_t n) {
    auto b = good;
    std::memcpy(b.data() + off, value, n);
    fixHeaderCrc(b);
    return b;
  };
  const std::uint32_t one = 1, seven = 7;
  const double spacing = 3.0;
  expectRefused(edit(8, &one, 4), "chart 'octahedral' needs format version 2, the header says 1");
  expectRefused(edit(100, &seven, 4),
                "chart variant 7 is not one of the 2 that chart 'octahedral'");
  expectRefused(edit(48, &spacing, 8), "an octahedral planet must store 0 in the flat spacing");
  const unsigned char byte = 1;
  expectRefused(edit(116, &byte, 1), "reserved header byte 116 is not zero");
  // A lat-long file may not carry a variant in version 1's reserved bytes.
  auto latlong = goodFile();
  std::memcpy(latlong.data() + 100, &one, 4);
  fixHeaderCrc(latlong);
  expectRefused(latlong, "reserved header byte 100 is not zero");
  // Heights that differ between the twins of a folded side: the grid does not fit its chart.
  auto twisted = good;
  const int m = t.grid().m();
  const float other = t.heights()[t.grid().index(3, 0)] + 100.0f;
  const std::size_t heightsAt = twisted.size() - t.heights().size() * 4;
  std::memcpy(twisted.data() + heightsAt + std::size_t(t.grid().index(m - 3, 0)) * 4, &other, 4);
  fixBodyCrc(twisted);
  expectRefused(twisted, "grid vertices at one point differ");
}

TEST(IoPlanetFile, TorusAndCylinderPlanetsRoundTripWithTheirLengths) {
  const core::GridSize g(5);
  std::vector<std::shared_ptr<const core::Chart>> charts = {
      std::make_shared<core::TorusChart>(g, 3000.0, 1000.0),
      std::make_shared<core::CylinderChart>(g, 1000.0, 5000.0)};
  for (const auto& chart : charts) {
    std::vector<float> h(g.count());
    for (int v = 0; v <= g.m(); ++v)
      for (int u = 0; u <= g.m(); ++u) {
        const core::GridPoint c = chart->canonical(u, v);
        h[g.index(u, v)] = float(20.0 * std::sin(0.3 * c.u) * std::cos(0.2 * c.v));
      }
    const auto bytes = io::encodePlanet(*chart, h, terrain::ErrorRule::kHybridExact);
    const io::PlanetData d = io::parsePlanet(bytes, chart->name() + ".planet");
    EXPECT_EQ(d.chart->name(), chart->name());
    EXPECT_EQ(core::dimsOf(*d.chart).radius, core::dimsOf(*chart).radius);
    EXPECT_EQ(core::dimsOf(*d.chart).minorRadius, core::dimsOf(*chart).minorRadius);
    EXPECT_EQ(core::dimsOf(*d.chart).length, core::dimsOf(*chart).length);
    EXPECT_EQ(d.heights, h);
    EXPECT_EQ(io::encodePlanet(*d.chart, d.heights, d.rule), bytes);
  }
  // Their second length is checked, and refused where another chart has none.
  auto torus = io::encodePlanet(*charts[0], std::vector<float>(g.count(), 0.0f),
                                terrain::ErrorRule::kHybridExact);
  const double tooThick = 4000.0, none = 0.0;
  std::memcpy(torus.data() + 104, &tooThick, 8);
  fixHeaderCrc(torus);
  expectRefused(torus, "minor radius 4000 m must be below the major radius 3000 m");
  std::memcpy(torus.data() + 104, &none, 8);
  fixHeaderCrc(torus);
  expectRefused(torus, "minor radius 0 m must be positive and finite");
  const auto octa = testkit::bumpyOctahedralTerrain(5, 2, 5000.0);
  auto o = io::encodePlanet(octa.chart(), octa.heights(), octa.bounds().rule());
  std::memcpy(o.data() + 104, &tooThick, 8);
  fixHeaderCrc(o);
  expectRefused(o, "an octahedral planet must store 0 in the second length field");
}

TEST(IoPlanetFile, EmptyTruncatedAndWrongTypeFilesAreRefusedByName) {
  expectRefused({}, "empty file");
  const auto good = goodFile();
  expectRefused({good.begin(), good.begin() + 5}, "not a PlanetSculpt planet file");
  expectRefused({good.begin(), good.begin() + 60},
                "truncated: 60 bytes, the header alone needs 128");
  for (std::size_t cut : {std::size_t(128), std::size_t(200), good.size() - 1}) {
    expectRefused({good.begin(), good.begin() + std::ptrdiff_t(cut)},
                  "truncated: " + std::to_string(cut) + " bytes");
  }
  auto longer = good;
  longer.push_back(0);
  expectRefused(longer, "1 unexpected bytes after the end");
  const std::vector<unsigned char> png = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n', 0, 0, 0, 13};
  expectRefused(png, "this is a PNG image");
  const std::string text = "hello, I am a text file\n";
  expectRefused({text.begin(), text.end()}, "not a PlanetSculpt planet file");
}

TEST(IoPlanetFile, EveryHeaderFieldIsChecked) {
  const auto good = goodFile();
  auto edit = [&](std::size_t off, const void* value, std::size_t n, bool fixCrc = true) {
    auto b = good;
    std::memcpy(b.data() + off, value, n);
    if (fixCrc) fixHeaderCrc(b);
    return b;
  };
  const std::uint32_t three = 3, zero = 0, nine = 9, huge = 1000001, side1025 = 1025;
  const double nan = std::nan(""), negative = -5.0, one = 1.0;
  expectRefused(edit(8, &three, 4), "format version 3 is not supported (this build reads 1 to 2)");
  expectRefused(edit(8, &zero, 4), "format version 0 is not supported");
  expectRefused(edit(12, &nine, 4), "header size field is 9");
  expectRefused(edit(16, "sphere", 7), "unknown chart 'sphere'");
  expectRefused(edit(16, "latlongXXXXXXXXX", 16), "chart name is not NUL-terminated");
  expectRefused(edit(32, &huge, 4), "grid side 1000001 is not 2^n + 1");
  expectRefused(edit(32, &side1025, 4), "height block is");  // a valid side the sizes do not match
  expectRefused(edit(36, &nine, 4), "unknown height encoding 9");
  expectRefused(edit(40, &nan, 8), "radius nan m must be positive and finite");
  expectRefused(edit(40, &negative, 8), "radius -5 m must be positive");
  expectRefused(edit(48, &one, 8), "a latlong planet must store 0 in the flat spacing fields");
  expectRefused(edit(64, &nan, 8), "height scale nan must be positive and finite");
  expectRefused(edit(72, &nan, 8), "height offset nan must be finite");
  expectRefused(edit(80, &nine, 4), "unknown error rule 9");
  const std::uint32_t bigMeta = 5u << 20;
  expectRefused(edit(84, &bigMeta, 4), "metadata block of 5242880 bytes exceeds the limit");
  const unsigned char one8 = 1;
  expectRefused(edit(110, &one8, 1), "reserved header byte 110 is not zero");
  // The header checksum itself.
  expectRefused(edit(40, &negative, 8, false), "header checksum mismatch");
}

TEST(IoPlanetFile, HugeDimensionsAreRefusedBeforeAnyAllocation) {
  // A header that claims a 2^20+1 grid (10^6 x 10^6 class): refused on the grid rule, and a
  // valid huge grid (32769^2, 4 GiB) in a small file is refused on the size before reading.
  auto b = goodFile();
  const std::uint32_t million = 1000001, big = 32769;
  std::memcpy(b.data() + 32, &million, 4);
  fixHeaderCrc(b);
  expectRefused(b, "grid side 1000001 is not 2^n + 1");
  const std::uint32_t side = (1u << 20) + 1;
  std::memcpy(b.data() + 32, &side, 4);
  fixHeaderCrc(b);
  expectRefused(b, "grid level n = 20 is out of range");
  std::memcpy(b.data() + 32, &big, 4);
  const std::uint64_t bytes = std::uint64_t(big) * big * 4;
  std::memcpy(b.data() + 88, &bytes, 8);
  fixHeaderCrc(b);
  expectRefused(b, "truncated: " + std::to_string(b.size()) + " bytes, the header announces");
  // Same through the file reader (which must not allocate 4 GiB either).
  const fs::path dir = testkit::freshDir("io_huge");
  writeAll(dir / "huge.planet", b);
  try {
    io::readPlanetFile(dir / "huge.planet");
    ADD_FAILURE() << "accepted";
  } catch (const core::InputError& e) {
    EXPECT_NE(std::string(e.what()).find((dir / "huge.planet").string() + ": truncated"),
              std::string::npos)
        << e.what();
  }
  fs::remove_all(dir);
}

TEST(IoPlanetFile, WrongChecksumNaNAndBrokenRulesAreRefused) {
  const auto good = goodFile();
  auto flipped = good;
  flipped[good.size() / 2] ^= 0x10;
  expectRefused(flipped, "checksum mismatch: stored CRC-32");

  // A NaN height with correct checksums: refused by vertex.
  auto withNan = good;
  const std::size_t metaBytes = [&] {
    std::uint32_t x;
    std::memcpy(&x, good.data() + 84, 4);
    return std::size_t(x);
  }();
  const std::size_t side = 33;
  const float nan = std::nanf("");
  std::memcpy(withNan.data() + 128 + metaBytes + 4 * (7 * side + 5), &nan, 4);
  fixBodyCrc(withNan);
  expectRefused(withNan, "height at vertex (u=5, v=7) is nan: heights must be finite");

  auto seam = good;
  const float odd = 1234.5f;
  std::memcpy(seam.data() + 128 + metaBytes + 4 * (9 * side + 0), &odd, 4);
  fixBodyCrc(seam);
  expectRefused(seam, "seam twins differ");

  auto meta = good;
  meta[128] = '[';
  fixBodyCrc(meta);
  expectRefused(meta, "metadata block is not a JSON object");
}

TEST(IoPlanetFile, MissingFileAndDirectoryAreNamed) {
  const fs::path dir = testkit::freshDir("io_missing");
  for (const fs::path& p : {dir / "nope.planet", dir}) {
    try {
      io::readPlanetFile(p);
      ADD_FAILURE();
    } catch (const core::InputError& e) {
      EXPECT_EQ(std::string(e.what()).rfind(p.string() + ": ", 0), 0u) << e.what();
    }
  }
  fs::remove_all(dir);
}

// A child process saves new versions of a planet in a loop and is killed, at points chosen
// without any clock: in half the trials a file-size limit (RLIMIT_FSIZE) set before its next
// save makes the kernel kill it (SIGXFSZ) at a random byte of that save; in the others it is
// sent SIGKILL as soon as it reports a save, landing wherever the next one has got to. After
// each kill the file must be, bit for bit, either the last version the child reported as saved
// or the one it was saving; it must load; and no kill may leave a partial file under the real
// name.
TEST(IoPlanetFile, KilledSavesLeaveTheLastGoodFileIntact) {
  const fs::path dir = testkit::freshDir("io_kill");
  const fs::path path = dir / "world.planet";
  auto chart = testkit::earthChart(8);  // 257^2: 264 kB per save
  const auto base = testkit::bumpyHeights(*chart, 5, 3000.0);
  auto version = [&](int k) {
    std::vector<float> h = base;
    for (float& x : h) x += float(k);
    return h;
  };
  auto bytesOf = [&](int k) {
    return io::encodePlanet(*chart, version(k), terrain::ErrorRule::kHybridExact);
  };
  io::savePlanet(*chart, version(0), terrain::ErrorRule::kHybridExact, path);
  const auto fileSize = bytesOf(0).size();
  int lastGood = 0;
  std::mt19937 rng(42);
  int interrupted = 0, completedSaves = 0;
  const int trials = 16;
  for (int trial = 0; trial < trials; ++trial) {
    int fds[2];
    ASSERT_EQ(::pipe(fds), 0);
    const int first = (trial + 1) * 1000;
    const int savesBefore = trial % 4;  // whole saves the child makes before the cut
    const bool byteLimit = trial % 2 == 0;
    const auto limit = rlim_t(std::uniform_int_distribution<std::size_t>(0, fileSize - 1)(rng));
    const pid_t pid = ::fork();
    ASSERT_GE(pid, 0);
    if (pid == 0) {
      ::close(fds[0]);
      const rlimit noCore{0, 0};
      ::setrlimit(RLIMIT_CORE, &noCore);
      try {
        for (int k = first;; ++k) {
          if (byteLimit && k == first + savesBefore) {
            const rlimit size{limit, limit};
            if (::setrlimit(RLIMIT_FSIZE, &size) != 0) ::_exit(5);
          }
          io::savePlanet(*chart, version(k), terrain::ErrorRule::kHybridExact, path);
          if (::write(fds[1], &k, sizeof k) != sizeof k) ::_exit(4);
        }
      } catch (...) {
        ::_exit(3);
      }
    }
    ::close(fds[1]);
    int k = 0, reported = -1;
    if (!byteLimit) {
      // Blocking reads: the child's own pace decides where the kill lands.
      for (int i = 0; i <= savesBefore && ::read(fds[0], &k, sizeof k) == sizeof k; ++i)
        reported = k;
      ::kill(pid, SIGKILL);
    }
    int status = 0;
    ::waitpid(pid, &status, 0);
    ASSERT_TRUE(WIFSIGNALED(status))
        << "the saving child failed on its own (status " << status << ")";
    while (::read(fds[0], &k, sizeof k) == sizeof k) reported = k;
    ::close(fds[0]);
    // Candidates: the last version reported saved (or the previous trial's), and the next one
    // (renamed but killed before it could report).
    const int done = reported >= 0 ? reported : lastGood;
    const int next = reported >= 0 ? reported + 1 : first;
    completedSaves += reported >= 0 ? reported - first + 1 : 0;
    const auto onDisk = readAll(path);
    int found = -1;
    for (int cand : {done, next}) {
      if (onDisk == bytesOf(cand)) found = cand;
    }
    ASSERT_NE(found, -1) << "trial " << trial << ": the file is neither version " << done << " nor "
                         << next << " (" << onDisk.size() << " bytes)";
    const auto loaded = io::readPlanetFile(path);
    const auto expect = version(found);
    ASSERT_EQ(std::memcmp(loaded.heights.data(), expect.data(), expect.size() * sizeof(float)), 0);
    lastGood = found;
    // A leftover temporary file means the kill landed inside a save before its rename.
    for (const auto& e : fs::directory_iterator(dir)) {
      if (e.path() != path) {
        ++interrupted;
        fs::remove(e.path());
      }
    }
  }
  std::cout << "[ kill test ] " << trials << " kills, " << interrupted
            << " inside a save before its rename, " << completedSaves
            << " saves completed by the children\n";
  EXPECT_GT(interrupted, 0) << "no kill landed inside a save: the test did not test anything";
  fs::remove_all(dir);
}
