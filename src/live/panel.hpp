#pragma once
// The live app's on-screen panel (Dear ImGui) and its keyboard shortcuts: what the user can
// change (tool, r_d, strength, raise/lower, the sand's material, dist_max, triangle budget,
// wireframe) and ask for (undo, redo, save, export, record), and what the app shows (frame rate,
// triangles, tracking state, autosave and journal, recording, messages), and the recovery question
// at start. Drawing only: the app (live/live_app.cpp) applies the settings and runs the actions.
#include <cstddef>
#include <string>
#include <vector>

namespace ps::live {

// The planet's radius on its marker (scaled by hand), in cm: from a marble to a beach ball.
inline constexpr float kPlanetSizeMinCm = 1.0f, kPlanetSizeMaxCm = 50.0f;

struct PanelSettings {
  bool displace = false;  // tool: brush (false) or sand displacement (true)
  bool tinSand = false;   // sand on a TIN (paper 000) instead of the grid's displacement
  float brushRadiusKm = 250, strengthM = 600, sigma = 0.17f;
  bool lower = false;  // brush: raise (false) or lower
  float displaceRadiusKm = 400, pressM = 8000;
  std::string material = "sand";  // the sand tools' (sand::Material::presetNames())
  float distMaxPx = 4;
  int triangleBudget = 70000;
  bool wireframe = false, contours = false;
  bool facets = false;  // shade each triangle from its geometry instead of per pixel
  bool showHelp = false, showOverview = true;
  float spinDeg = 0, tiltDeg = 0;  // the planet turned by hand on its marker
  // Where the light comes from, in the planet's frame (longitude, latitude of the sub-solar
  // point): 45, 35 is the renderer's default sun (1, 1, 1).
  float sunLonDeg = 45, sunLatDeg = 35.26f;
  bool boardShadow = true, atmosphere = true;  // the planet's shadow on the board, the rim
  bool handMask = true;    // the camera image over the planet where a hand is in front of it
  float planetSizeCm = 6;  // the planet's radius on its marker, scaled by hand
  bool operator==(const PanelSettings&) const = default;
};

struct PanelActions {
  bool undo = false, redo = false, save = false, quit = false;
  bool exportPlanet = false;  // heightmap + mesh into OUT/exports/
  bool record = false;        // start or stop recording the camera frames
  bool crash = false;         // scripted only: end the process as a crash would (SIGKILL)
  bool interrupt = false;     // scripted only: Ctrl-C (SIGINT) to this process
};

// An action taken at a window frame as if its key were pressed then (`live --at FRAME:ACTION`),
// or a panel setting changed then (`--at FRAME:SETTING=VALUE`): scripted sessions for tests and
// demos, independent of how fast the frames come.
struct ScriptedAction {
  int frame = 0;
  std::string action;  // export, record, save, undo, redo, quit, interrupt, crash; "" : a setting
  // tool (brush, displace, tin-sand), mode (raise, lower), material (sand, mud, pebbles),
  // radius_km, strength_m, sigma, displace_radius_km, press_m, size_cm, spin_deg, tilt_deg
  std::string setting;
  std::string word;  // tool, mode, material
  float number = 0;  // the others
};
// Parses "FRAME:ACTION" or "FRAME:SETTING=VALUE"; throws core::InputError naming the text
// otherwise. (Values out of the panel's range are refused when applied, as a typed one is.)
ScriptedAction parseScriptedAction(const std::string& text);
// Adds the actions scripted for `frame` to `actions` and sets its settings in `settings`.
void applyScript(const std::vector<ScriptedAction>& script, int frame, PanelActions& actions,
                 PanelSettings& settings);

struct PanelStatus {
  double fps = 0, frameMs = 0, trackMs = 0, editMs = 0, tessellateMs = 0, renderMs = 0;
  std::size_t triangles = 0;
  bool reused = false;  // the tessellator handed back its previous mesh
  std::string planetState, toolState;
  bool touching = false;
  double forceN = 0, hapticHz = 0;  // the haptic loop's last force and its rate
  std::size_t undoCount = 0, redoCount = 0;
  std::string message;  // camera lost, video ended, saved, errors
  std::string savePath;
  double autosaveInS = -1;         // seconds to the next autosave (< 0: off)
  std::size_t journalRecords = 0;  // records in OUT/planet.journal since the last save
  std::string recordPath;          // "" when not recording
  int recordedFrames = 0;
  std::string exportPath;  // the last export ("" before the first)
};

// The recovery question (a modal) while a crashed session's journal waits for an answer.
enum class RecoveryAnswer { kNone, kRecover, kDiscard };
RecoveryAnswer drawRecoveryModal(const std::string& message);

// The shortcuts, as listed by `?` (and by `planetsculpt live --help`).
const char* shortcutHelp();

// Reads this frame's keys and mouse (ImGui's io, GLFW key codes) into settings and actions:
// keys go to the panel's own fields while one has the keyboard; a right-button drag outside
// the panel turns the planet.
void applyShortcuts(PanelSettings& settings, PanelActions& actions);

// Draws the panel (and the help window when settings.showHelp).
// Returns the panel's bottom edge (display units), for what goes below it in its column.
float drawControlPanel(PanelSettings& settings, PanelActions& actions, const PanelStatus& status);

}  // namespace ps::live
