// `planetsculpt markers --out DIR`: print-ready sheets of the planet board and the tool cube's net
// (from their layouts, markers/*.json), the single planet and tool markers and the ChArUco
// calibration board, for A4 and US Letter, as 1-bit 300-dpi PNG and one-page PDF
// (tracking/marker_sheet.hpp), and the board's and the tool's layout files (planet-board.json,
// tool-cube.json) in the family and size printed. Defaults are the tracker's
// (tracking::SceneConfig): tag36h11, planet id 0 of 80 mm, tool id 1 of 50 mm with its tip 80 mm
// below the marker centre.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>

#include "app/build_paths.hpp"
#include "app/command_registry.hpp"
#include "core/input_error.hpp"
#include "tracking/detector.hpp"
#include "tracking/marker_layout.hpp"
#include "tracking/marker_sheet.hpp"
#include "tracking/tracker.hpp"

namespace ps::app {

namespace {

struct MarkersArgs {
  std::string out = "markers", paper = "both", format = "both";
  std::string family = tracking::DetectorConfig{}.family;
  int planetId = tracking::SceneConfig{}.planet.id, toolId = tracking::SceneConfig{}.tool.id;
  double planetMm = tracking::SceneConfig{}.planet.size * 1e3;
  double toolMm = tracking::SceneConfig{}.tool.size * 1e3;
  double planetRadiusMm = tracking::SceneConfig{}.planetRadius * 1e3;
  std::vector<double> tipMm = {tracking::SceneConfig{}.tipOffset.x() * 1e3,
                               tracking::SceneConfig{}.tipOffset.y() * 1e3,
                               tracking::SceneConfig{}.tipOffset.z() * 1e3};
  std::string squares = "5x7";
  double squareMm = 30, markerMm = 22;
  std::string dictionary = "DICT_5X5_100";
  double dpi = 300;
  std::string board = (sourceDir() / "markers" / "planet-board.json").string();
  std::string toolLayout = (sourceDir() / "markers" / "tool-cube.json").string();
  // The board's and the tool's family and marker edge (empty, 0: --family when given, else the
  // layout's; the layout's size).
  std::string boardFamily, toolFamily;
  double boardMarkerMm = 0, toolMarkerMm = 0;
  bool familyGiven = false;
};

// Written next to the target and renamed: a crash never leaves half a sheet under its name.
void writeFile(const std::filesystem::path& path, const std::vector<std::uint8_t>& bytes) {
  const std::filesystem::path tmp = path.string() + ".part";
  {
    std::ofstream f(tmp, std::ios::binary | std::ios::trunc);
    if (!f) throw std::runtime_error("cannot write " + tmp.string());
    f.write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
    f.flush();
    if (!f) throw std::runtime_error("cannot write " + tmp.string());
  }
  std::filesystem::rename(tmp, path);
}

// The layout as printed: its family (the option, else --family when given, else its own) and
// marker edge.
tracking::MarkerLayout printedLayout(const MarkersArgs& a, const std::string& path,
                                     const std::string& family, double markerMm) {
  const tracking::MarkerLayout l = tracking::loadMarkerLayout(path);
  const std::string f = !family.empty() ? family : a.familyGiven ? a.family : l.family;
  return tracking::resizedLayout(l, f, markerMm * 1e-3);
}

// Writes a printed layout beside its sheets, unless the file there already holds that layout
// (the committed markers/*.json, when the sheets are made again into markers/).
void writeLayout(const std::filesystem::path& path, const tracking::MarkerLayout& layout) {
  const std::string text = tracking::layoutFileText(layout);
  if (std::filesystem::exists(path)) {
    try {
      if (tracking::layoutFileText(tracking::loadMarkerLayout(path)) == text) {
        std::cerr << "markers: " << path.string() << " (unchanged)\n";
        return;
      }
    } catch (const core::InputError&) {
      // not a layout (or a broken one): written over, as the sheets are
    }
  }
  writeFile(path, std::vector<std::uint8_t>(text.begin(), text.end()));
  std::cerr << "markers: " << path.string() << " (layout: " << layout.family << ", "
            << layout.markers.size() << " markers of "
            << std::lround(layout.markers.front().edge() * 1e4) / 10.0 << " mm)\n";
}

tracking::CharucoBoardSpec boardFrom(const MarkersArgs& a) {
  tracking::CharucoBoardSpec b;
  if (std::sscanf(a.squares.c_str(), "%dx%d", &b.squaresX, &b.squaresY) != 2)
    throw core::InputError("--squares '" + a.squares + "' is not COLUMNSxROWS (e.g. 5x7)");
  b.squareLength = a.squareMm * 1e-3;
  b.markerLength = a.markerMm * 1e-3;
  b.dictionary = a.dictionary;
  b.validate();
  return b;
}

int runMarkers(const MarkersArgs& a) {
  std::vector<tracking::Paper> papers;
  if (a.paper == "both") {
    papers = {tracking::paperA4(), tracking::paperLetter()};
  } else {
    papers = {tracking::paperFromString(a.paper)};
  }
  if (a.format != "png" && a.format != "pdf" && a.format != "both")
    throw core::InputError("--format '" + a.format + "' is not one of png, pdf, both");
  if (a.tipMm.size() != 3) throw core::InputError("--tip-mm needs three numbers X,Y,Z");
  if (a.planetId == a.toolId)
    throw core::InputError("the planet and tool markers need different ids (both are " +
                           std::to_string(a.planetId) + ")");
  const auto board = boardFrom(a);
  const tracking::MarkerLayout planetBoard =
      printedLayout(a, a.board, a.boardFamily, a.boardMarkerMm);
  const tracking::MarkerLayout toolCube =
      printedLayout(a, a.toolLayout, a.toolFamily, a.toolMarkerMm);
  // What `live --board FILE --tool-layout FILE` will refuse: one id on both, in one family.
  {
    tracking::SceneConfig scene;
    scene.useBoard(std::make_shared<const tracking::MarkerLayout>(planetBoard));
    scene.useToolLayout(std::make_shared<const tracking::MarkerLayout>(toolCube));
    scene.validate();
  }
  tracking::MarkerSheetSpec planet;
  planet.family = a.family;
  planet.id = a.planetId;
  planet.sizeMm = a.planetMm;
  planet.planetRadiusMm = a.planetRadiusMm;
  tracking::MarkerSheetSpec tool = planet;
  tool.id = a.toolId;
  tool.sizeMm = a.toolMm;
  tool.tool = true;
  tool.tipOffsetMm = {a.tipMm[0], a.tipMm[1], a.tipMm[2]};
  const std::filesystem::path dir = a.out;
  std::filesystem::create_directories(dir);
  writeLayout(dir / "planet-board.json", planetBoard);
  writeLayout(dir / "tool-cube.json", toolCube);
  long long total = 0;
  for (const auto& paper : papers) {
    const std::pair<std::string, tracking::Sheet> sheets[5] = {
        {"planet-board", tracking::renderBoardSheet(planetBoard, paper, a.dpi)},
        {"tool-cube", tracking::renderCubeNetSheet(toolCube, paper, a.dpi)},
        {"planet-marker", tracking::renderMarkerSheet(planet, paper, a.dpi)},
        {"tool-marker", tracking::renderMarkerSheet(tool, paper, a.dpi)},
        {"charuco-board", tracking::renderCharucoSheet(board, paper, a.dpi)}};
    for (const auto& [stem, sheet] : sheets) {
      const std::string base = stem + "-" + paper.tag;
      if (a.format != "pdf") {
        const auto png = tracking::encodeSheetPng(sheet.image, sheet.dpi);
        writeFile(dir / (base + ".png"), png);
        total += (long long)png.size();
        std::cerr << "markers: " << (dir / (base + ".png")).string() << " (" << sheet.image.cols
                  << "x" << sheet.image.rows << ", " << png.size() / 1024 << " KiB)\n";
      }
      if (a.format != "png") {
        const auto pdf = tracking::encodeSheetPdf(sheet);
        writeFile(dir / (base + ".pdf"), pdf);
        total += (long long)pdf.size();
        std::cerr << "markers: " << (dir / (base + ".pdf")).string() << " (" << pdf.size() / 1024
                  << " KiB)\n";
      }
    }
  }
  std::cerr << "markers: " << total / 1024 << " KiB in all. Print at 100 % (actual size) and "
            << "measure the 100 mm bar.\n";
  return 0;
}

const CommandRegistration kMarkers([](CLI::App& root, CLI::App*& sub) -> CommandAction {
  auto a = std::make_shared<MarkersArgs>();
  sub = root.add_subcommand(
      "markers",
      "Write print-ready sheets (planet board, tool cube net, single planet and tool markers, "
      "ChArUco board; A4 and US Letter; 300-dpi PNG and PDF) and the board's and tool's layout "
      "files beside them");
  sub->add_option("--out", a->out, "Folder to write the sheets to")->capture_default_str();
  sub->add_option("--paper", a->paper, "a4, letter or both")->capture_default_str();
  sub->add_option("--format", a->format, "png, pdf or both")->capture_default_str();
  sub->add_option("--dpi", a->dpi, "Resolution")->capture_default_str();
  sub->add_option("--family", a->family,
                  "Marker family of every sheet (tag36h11, DICT_6X6_250, ...); the board and the "
                  "tool keep their layouts' unless given")
      ->capture_default_str();
  sub->add_option("--board-family", a->boardFamily,
                  "The board's family (default: --family when given, else its layout's)");
  sub->add_option("--board-marker-mm", a->boardMarkerMm,
                  "The board's marker edge (mm; the whole board scales; default: its layout's)");
  sub->add_option("--tool-family", a->toolFamily,
                  "The tool cube's family (default: --family when given, else its layout's)");
  sub->add_option("--tool-marker-mm", a->toolMarkerMm,
                  "The tool cube's marker edge (mm; the cube and its tip scale; default: its "
                  "layout's)");
  sub->add_option("--board", a->board, "Planet board layout (JSON)")->capture_default_str();
  sub->add_option("--tool-layout", a->toolLayout, "Tool cube layout (JSON)")->capture_default_str();
  sub->add_option("--planet-id", a->planetId, "Planet marker id")->capture_default_str();
  sub->add_option("--planet-mm", a->planetMm, "Planet marker edge (mm)")->capture_default_str();
  sub->add_option("--planet-radius-mm", a->planetRadiusMm, "Planet radius (mm; printed only)")
      ->capture_default_str();
  sub->add_option("--tool-id", a->toolId, "Tool marker id")->capture_default_str();
  sub->add_option("--tool-mm", a->toolMm, "Tool marker edge (mm)")->capture_default_str();
  sub->add_option("--tip-mm", a->tipMm, "Tool tip in the tool marker's frame X,Y,Z (mm)")
      ->delimiter(',')
      ->expected(3);
  sub->add_option("--squares", a->squares, "ChArUco board squares COLUMNSxROWS (rows odd)")
      ->capture_default_str();
  sub->add_option("--square-mm", a->squareMm, "ChArUco square edge (mm)")->capture_default_str();
  sub->add_option("--marker-mm", a->markerMm, "ChArUco marker edge (mm)")->capture_default_str();
  sub->add_option("--dictionary", a->dictionary, "ChArUco board dictionary")->capture_default_str();
  const CLI::Option* family = sub->get_option("--family");
  return [a, family] {
    a->familyGiven = family->count() > 0;
    return runMarkers(*a);
  };
});

}  // namespace
}  // namespace ps::app
