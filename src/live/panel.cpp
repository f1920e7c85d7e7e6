#include "live/panel.hpp"

#define GLFW_INCLUDE_NONE  // key codes only
#include <GLFW/glfw3.h>
#include <imgui.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <exception>
#include <iterator>

#include "core/input_error.hpp"
#include "live/window_layout.hpp"
#include "sand/material.hpp"

namespace ps::live {

namespace {

// The panel fields a script may set, by name.
float* scriptedNumber(PanelSettings& s, const std::string& name) {
  if (name == "radius_km") return &s.brushRadiusKm;
  if (name == "strength_m") return &s.strengthM;
  if (name == "sigma") return &s.sigma;
  if (name == "displace_radius_km") return &s.displaceRadiusKm;
  if (name == "press_m") return &s.pressM;
  if (name == "size_cm") return &s.planetSizeCm;
  if (name == "spin_deg") return &s.spinDeg;
  if (name == "tilt_deg") return &s.tiltDeg;
  return nullptr;
}

}  // namespace

ScriptedAction parseScriptedAction(const std::string& text) {
  static const char* const kActions[] = {"export", "record", "save", "undo", "redo", "quit"};
  // Test-only actions, outside the user's command surface: the live smoke test sets
  // PS_TEST_ACTIONS=1 to script a Ctrl-C (interrupt) or a crash (SIGKILL) at a frame.
  static const char* const kTestActions[] = {"interrupt", "crash"};
  const char* testEnv = std::getenv("PS_TEST_ACTIONS");
  const bool testActions = testEnv && std::string(testEnv) == "1";
  const auto colon = text.find(':');
  ScriptedAction a;
  std::size_t used = 0;
  try {
    if (colon != std::string::npos) a.frame = std::stoi(text.substr(0, colon), &used);
  } catch (const std::exception&) {
    used = 0;
  }
  a.action = colon == std::string::npos ? "" : text.substr(colon + 1);
  bool known =
      std::find(std::begin(kActions), std::end(kActions), a.action) != std::end(kActions) ||
      (testActions && std::find(std::begin(kTestActions), std::end(kTestActions), a.action) !=
                          std::end(kTestActions));
  const auto eq = a.action.find('=');
  if (!known && eq != std::string::npos) {
    a.setting = a.action.substr(0, eq);
    const std::string value = a.action.substr(eq + 1);
    a.action.clear();
    if (a.setting == "tool")
      known = value == "brush" || value == "displace" || value == "tin-sand";
    else if (a.setting == "mode")
      known = value == "raise" || value == "lower";
    else if (a.setting == "material")
      known = std::ranges::find(sand::Material::presetNames(), value) !=
              sand::Material::presetNames().end();
    else if (PanelSettings probe; scriptedNumber(probe, a.setting)) {
      std::size_t n = 0;
      try {
        a.number = std::stof(value, &n);
      } catch (const std::exception&) {
        n = 0;
      }
      known = n > 0 && n == value.size() && std::isfinite(a.number);
    }
    a.word = value;
  }
  if (colon == std::string::npos || used != colon || a.frame < 0 || !known) {
    throw core::InputError("--at " + text +
                           ": expected FRAME:ACTION with FRAME >= 0 and ACTION one of export, "
                           "record, save, undo, redo, quit, or FRAME:SETTING="
                           "VALUE with tool=brush|displace|tin-sand, mode=raise|lower, "
                           "material=sand|mud|pebbles or a number for "
                           "radius_km, strength_m, sigma, displace_radius_km, press_m, size_cm, "
                           "spin_deg, tilt_deg");
  }
  return a;
}

void applyScript(const std::vector<ScriptedAction>& script, int frame, PanelActions& a,
                 PanelSettings& settings) {
  for (const ScriptedAction& s : script) {
    if (s.frame != frame) continue;
    a.exportPlanet |= s.action == "export";
    a.record |= s.action == "record";
    a.save |= s.action == "save";
    a.undo |= s.action == "undo";
    a.redo |= s.action == "redo";
    a.quit |= s.action == "quit";
    a.crash |= s.action == "crash";
    a.interrupt |= s.action == "interrupt";
    if (s.setting == "tool") {
      settings.displace = s.word == "displace" || s.word == "tin-sand";
      settings.tinSand = s.word == "tin-sand";
    }
    if (s.setting == "mode") settings.lower = s.word == "lower";
    if (s.setting == "material") settings.material = s.word;
    if (float* f = scriptedNumber(settings, s.setting)) *f = s.number;
  }
}

const char* shortcutHelp() {
  return "?  or F1     this help\n"
         "B            tool: brush\n"
         "D            tool: displace (sand)\n"
         "R            brush: raise / lower\n"
         "[  ]         r_d smaller / larger (x 0.8 / x 1.25)\n"
         "-  =         strength smaller / larger\n"
         "W            wireframe\n"
         "F            facets: shade each triangle (the tessellation shows) / per pixel\n"
         "C            contour lines\n"
         "O            overview inset\n"
         "Left/Right   turn the planet about its axis (5 degrees; or drag, right button)\n"
         "Up/Down      tilt the planet (5 degrees)\n"
         "PgUp/PgDn    planet larger / smaller on its marker (x 1.25; or the mouse wheel)\n"
         "Home         planet back as the marker holds it\n"
         "Ctrl+Z       undo the last stroke\n"
         "Ctrl+Y, Ctrl+Shift+Z   redo\n"
         "Ctrl+S       save the planet (OUT/planet.planet; also autosaved every minute)\n"
         "Ctrl+E       export heightmap (16-bit PNG + .json) and mesh (.glb) to OUT/exports/\n"
         "Ctrl+R       start / stop recording the camera frames (OUT/recording-NNN.mkv)\n"
         "Esc          save and quit (also: close the window, Ctrl-C)\n";
}

void applyShortcuts(PanelSettings& s, PanelActions& a) {
  const ImGuiIO& io = ImGui::GetIO();
  if (io.WantTextInput) return;
  auto pressed = [](int key) { return ImGui::IsKeyPressed(key, false); };
  if ((pressed(GLFW_KEY_SLASH) && io.KeyShift) || pressed(GLFW_KEY_F1)) s.showHelp = !s.showHelp;
  if (io.KeyCtrl) {
    if (pressed(GLFW_KEY_Z)) (io.KeyShift ? a.redo : a.undo) = true;
    if (pressed(GLFW_KEY_Y)) a.redo = true;
    if (pressed(GLFW_KEY_S)) a.save = true;
    if (pressed(GLFW_KEY_E)) a.exportPlanet = true;
    if (pressed(GLFW_KEY_R)) a.record = true;
    return;
  }
  if (pressed(GLFW_KEY_B)) s.displace = false, s.tinSand = false;
  if (pressed(GLFW_KEY_D)) s.displace = true, s.tinSand = false;
  if (pressed(GLFW_KEY_R)) s.lower = !s.lower;
  if (pressed(GLFW_KEY_W)) s.wireframe = !s.wireframe;
  if (pressed(GLFW_KEY_F)) s.facets = !s.facets;
  if (pressed(GLFW_KEY_C)) s.contours = !s.contours;
  if (pressed(GLFW_KEY_O)) s.showOverview = !s.showOverview;
  if (pressed(GLFW_KEY_LEFT_BRACKET)) s.brushRadiusKm = std::max(20.f, s.brushRadiusKm * 0.8f);
  if (pressed(GLFW_KEY_RIGHT_BRACKET)) s.brushRadiusKm = std::min(2000.f, s.brushRadiusKm * 1.25f);
  if (pressed(GLFW_KEY_MINUS)) s.strengthM = std::max(10.f, s.strengthM * 0.8f);
  if (pressed(GLFW_KEY_EQUAL)) s.strengthM = std::min(5000.f, s.strengthM * 1.25f);
  if (pressed(GLFW_KEY_ESCAPE)) a.quit = true;
  auto wrap = [](float deg) { return std::remainder(deg, 360.f); };
  if (ImGui::IsKeyPressed(GLFW_KEY_LEFT)) s.spinDeg = wrap(s.spinDeg - 5);
  if (ImGui::IsKeyPressed(GLFW_KEY_RIGHT)) s.spinDeg = wrap(s.spinDeg + 5);
  if (ImGui::IsKeyPressed(GLFW_KEY_UP)) s.tiltDeg = std::min(90.f, s.tiltDeg + 5);
  if (ImGui::IsKeyPressed(GLFW_KEY_DOWN)) s.tiltDeg = std::max(-90.f, s.tiltDeg - 5);
  if (pressed(GLFW_KEY_HOME)) s.spinDeg = s.tiltDeg = 0;
  auto resize = [&](float factor) {
    s.planetSizeCm = std::clamp(s.planetSizeCm * factor, kPlanetSizeMinCm, kPlanetSizeMaxCm);
  };
  if (ImGui::IsKeyPressed(GLFW_KEY_PAGE_UP)) resize(1.25f);
  if (ImGui::IsKeyPressed(GLFW_KEY_PAGE_DOWN)) resize(0.8f);
  if (!io.WantCaptureMouse && io.MouseWheel != 0) resize(std::pow(1.1f, io.MouseWheel));
  if (!io.WantCaptureMouse && ImGui::IsMouseDragging(ImGuiMouseButton_Right)) {
    s.spinDeg = wrap(s.spinDeg + 0.3f * io.MouseDelta.x);
    s.tiltDeg = std::clamp(s.tiltDeg + 0.3f * io.MouseDelta.y, -90.f, 90.f);
  }
}

float drawControlPanel(PanelSettings& s, PanelActions& a, const PanelStatus& st) {
  // Docked in the column at the right (live/window_layout.hpp), beside the AR view.
  const ImVec2 display = ImGui::GetIO().DisplaySize;
  ImGui::SetNextWindowPos(ImVec2(display.x - kSideColumnWidth + 4, 4), ImGuiCond_Always);
  ImGui::SetNextWindowSize(ImVec2(kSideColumnWidth - 8, 0), ImGuiCond_Always);
  ImGui::SetNextWindowBgAlpha(0.9f);
  ImGui::Begin("PlanetSculpt", nullptr,
               ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoCollapse);
  ImGui::PushItemWidth(-150);  // sliders leave room for their labels
  ImGui::PushTextWrapPos(0);   // long lines wrap at the column's edge
  ImGui::Text("%.1f fps, %.1f ms a frame", st.fps, st.frameMs);
  ImGui::Text("track %.1f  edit %.1f  tess %.1f  render %.1f ms", st.trackMs, st.editMs,
              st.tessellateMs, st.renderMs);
  ImGui::Text("triangles %zu%s", st.triangles, st.reused ? "  (view unchanged: reused)" : "");
  ImGui::Text("planet: %s   tool: %s%s", st.planetState.c_str(), st.toolState.c_str(),
              st.touching ? "   TOUCHING" : "");
  ImGui::Text("haptic force %.2f N (%.0f Hz loop; drawn, not felt)", st.forceN, st.hapticHz);
  if (!st.message.empty()) ImGui::TextColored(ImVec4(1, 0.4f, 0.3f, 1), "%s", st.message.c_str());
  ImGui::Separator();
  int tool = s.displace ? (s.tinSand ? 2 : 1) : 0;
  ImGui::RadioButton("brush (B)", &tool, 0);
  ImGui::SameLine();
  ImGui::RadioButton("displace (D)", &tool, 1);
  ImGui::SameLine();
  ImGui::RadioButton("sand TIN", &tool, 2);
  s.displace = tool >= 1;
  s.tinSand = tool == 2;
  if (!s.displace) {
    ImGui::SliderFloat("r_d (km)", &s.brushRadiusKm, 20, 2000, "%.0f",
                       ImGuiSliderFlags_Logarithmic);
    ImGui::SliderFloat("strength (m)", &s.strengthM, 10, 5000, "%.0f",
                       ImGuiSliderFlags_Logarithmic);
    ImGui::SliderFloat("sigma", &s.sigma, 0.05f, 1.0f, "%.2f");
    int lower = s.lower ? 1 : 0;
    ImGui::RadioButton("raise", &lower, 0);
    ImGui::SameLine();
    ImGui::RadioButton("lower (R)", &lower, 1);
    s.lower = lower == 1;
  } else {
    ImGui::SliderFloat("sphere r (km)", &s.displaceRadiusKm, 50, 2000, "%.0f",
                       ImGuiSliderFlags_Logarithmic);
    ImGui::SliderFloat("press (m)", &s.pressM, 500, 50000, "%.0f", ImGuiSliderFlags_Logarithmic);
    const auto& names = sand::Material::presetNames();
    for (std::size_t i = 0; i < names.size(); ++i) {
      if (i > 0) ImGui::SameLine();
      if (ImGui::RadioButton(names[i].c_str(), s.material == names[i])) s.material = names[i];
    }
  }
  ImGui::Separator();
  ImGui::SliderFloat("dist_max (px)", &s.distMaxPx, 0.25f, 16, "%.2f",
                     ImGuiSliderFlags_Logarithmic);
  ImGui::SliderInt("triangle budget", &s.triangleBudget, 5000, 500000, "%d",
                   ImGuiSliderFlags_Logarithmic);
  ImGui::Checkbox("wireframe (W)", &s.wireframe);
  ImGui::SameLine(ImGui::GetWindowWidth() * 0.5f);
  ImGui::Checkbox("contours (C)", &s.contours);
  ImGui::Checkbox("overview (O)", &s.showOverview);
  ImGui::SameLine(ImGui::GetWindowWidth() * 0.5f);
  ImGui::Checkbox("facets (F)", &s.facets);
  ImGui::SliderFloat("sun longitude", &s.sunLonDeg, -180, 180, "%.0f deg");
  ImGui::SliderFloat("sun latitude", &s.sunLatDeg, -90, 90, "%.0f deg");
  ImGui::Checkbox("board shadow", &s.boardShadow);
  ImGui::SameLine(ImGui::GetWindowWidth() * 0.5f);
  ImGui::Checkbox("atmosphere", &s.atmosphere);
  ImGui::Checkbox("hand mask", &s.handMask);
  ImGui::SliderFloat("spin (Left/Right)", &s.spinDeg, -180, 180, "%.0f deg");
  ImGui::SliderFloat("tilt (Up/Down)", &s.tiltDeg, -90, 90, "%.0f deg");
  if (ImGui::Button("reset")) s.spinDeg = s.tiltDeg = 0;
  ImGui::SameLine();
  ImGui::Text("planet radius %.1f cm (PgUp/PgDn)", double(s.planetSizeCm));
  ImGui::Separator();
  if (ImGui::Button("undo (Ctrl+Z)")) a.undo = true;
  ImGui::SameLine();
  if (ImGui::Button("redo (Ctrl+Y)")) a.redo = true;
  ImGui::SameLine();
  ImGui::Text("%zu / %zu", st.undoCount, st.redoCount);
  ImGui::SameLine();
  if (ImGui::Button("save (Ctrl+S)")) a.save = true;
  if (st.autosaveInS >= 0)
    ImGui::TextDisabled("%s; autosave in %.0f s; %zu journal records since", st.savePath.c_str(),
                        st.autosaveInS, st.journalRecords);
  else
    ImGui::TextDisabled("%s; autosave off; %zu journal records since", st.savePath.c_str(),
                        st.journalRecords);
  if (ImGui::Button("export (Ctrl+E)")) a.exportPlanet = true;
  ImGui::SameLine();
  if (ImGui::Button(st.recordPath.empty() ? "record (Ctrl+R)" : "stop rec (Ctrl+R)"))
    a.record = true;
  ImGui::SameLine();
  if (ImGui::Button("keys (?)")) s.showHelp = !s.showHelp;
  ImGui::TextDisabled("%s", st.exportPath.empty() ? "exports: heightmap + mesh to OUT/exports/"
                                                  : st.exportPath.c_str());
  if (!st.recordPath.empty()) {
    ImGui::TextColored(ImVec4(1, 0.3f, 0.3f, 1), "REC %d frames -> %s", st.recordedFrames,
                       st.recordPath.c_str());
  }
  ImGui::PopTextWrapPos();
  ImGui::PopItemWidth();
  const float bottom = ImGui::GetWindowPos().y + ImGui::GetWindowSize().y;
  ImGui::End();
  if (s.showHelp) {
    ImGui::Begin("Shortcuts", &s.showHelp, ImGuiWindowFlags_AlwaysAutoResize);
    ImGui::TextUnformatted(shortcutHelp());
    ImGui::End();
  }
  return bottom;
}

RecoveryAnswer drawRecoveryModal(const std::string& message) {
  const char* title = "Recover the last session's strokes?";
  if (!ImGui::IsPopupOpen(title)) ImGui::OpenPopup(title);
  RecoveryAnswer answer = RecoveryAnswer::kNone;
  const ImVec2 display = ImGui::GetIO().DisplaySize;
  ImGui::SetNextWindowPos(ImVec2(display.x * 0.5f, display.y * 0.5f), ImGuiCond_Always,
                          ImVec2(0.5f, 0.5f));
  if (ImGui::BeginPopupModal(title, nullptr, ImGuiWindowFlags_AlwaysAutoResize)) {
    ImGui::PushTextWrapPos(ImGui::GetFontSize() * 40);
    ImGui::TextUnformatted(message.c_str());
    ImGui::PopTextWrapPos();
    ImGui::Separator();
    if (ImGui::Button("Recover")) answer = RecoveryAnswer::kRecover;
    ImGui::SameLine();
    if (ImGui::Button("Discard")) answer = RecoveryAnswer::kDiscard;
    ImGui::TextDisabled(
        "Discard keeps the journal as planet.journal.discarded.\n"
        "Closing the window (or Esc) leaves both files as they are.");
    if (answer != RecoveryAnswer::kNone) ImGui::CloseCurrentPopup();
    ImGui::EndPopup();
  }
  return answer;
}

}  // namespace ps::live
