// `planetsculpt markers --out DIR`: print-ready sheets of the planet board and the tool cube's net
// (from their layouts, markers/*.json), the single planet and tool markers and the ChArUco
// calibration board, for A4 and US Letter, as 1-bit 300-dpi PNG and one-page PDF
// (tracking/marker_sheet.hpp). Defaults are the tracker's (tracking::SceneConfig): tag36h11,
// planet id 0 of 80 mm, tool id 1 of 50 mm with its tip 80 mm below the marker centre.
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
  const tracking::MarkerLayout planetBoard = tracking::loadMarkerLayout(a.board);
  const tracking::MarkerLayout toolCube = tracking::loadMarkerLayout(a.toolLayout);
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
      "ChArUco board; A4 and US Letter; 300-dpi PNG and PDF)");
  sub->add_option("--out", a->out, "Folder to write the sheets to")->capture_default_str();
  sub->add_option("--paper", a->paper, "a4, letter or both")->capture_default_str();
  sub->add_option("--format", a->format, "png, pdf or both")->capture_default_str();
  sub->add_option("--dpi", a->dpi, "Resolution")->capture_default_str();
  sub->add_option("--family", a->family, "Marker family (tag36h11, DICT_6X6_250, ...)")
      ->capture_default_str();
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
  return [a] { return runMarkers(*a); };
});

}  // namespace
}  // namespace ps::app
