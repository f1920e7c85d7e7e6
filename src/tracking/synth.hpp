#pragma once
// Synthetic marker videos with exact ground truth: scripted camera and tool trajectories over a
// textured table, the planet marker lying on the table, the tool marker on a stick; lighting
// change, defocus blur, motion blur, sensor noise, partial occlusion and markers leaving the
// frame. Rendering is deterministic (same script, same bytes) and exact to the pixel
// convention: marker edges are anti-aliased at 8x8 samples per pixel.
//
// Script (JSON):
//   { "size": [640, 480], "fps": 30, "seed": 1, "family": "tag36h11",
//     "camera": {"fx": 600, "fy": 600, "cx": 319.5, "cy": 239.5},      (optional; default)
//     "planet": {"id": 0, "size": 0.08, "radius": 0.06},
//     "tool": {"id": 1, "size": 0.05, "tip": [0, -0.08, 0]},
//     "exposure": 0.0, "motion_samples": 1, "table": "wood",
//     "keys": [ {"frame": 0,
//                "camera": {"distance": 0.6, "elevation": 50, "azimuth": -90, "roll": 0},
//                "tip": {"lat": 40, "lon": -90, "height_mm": 20},
//                "tool": {"tilt": 20, "turn": 0},
//                "blur": 0.4, "noise": 1.0, "gain": 1.0, "occlusion": 0.0}, ... ] }
// Keys are interpolated with a smoothstep between consecutive key frames (values not given in
// a key carry over from the previous key); the video has keys.back().frame + 1 frames.
//   camera: orbit around the planet's centre (distance m, elevation and azimuth in degrees;
//           azimuth -90 puts the camera on the planet frame's -y side, looking along +y).
//   tip:    the tool tip in the planet frame: latitude/longitude (degrees; latitude 90 is the
//           north pole, above the planet marker) and height above the planet's surface (mm).
//   tool:   the stick runs from the tip across the line of sight, away from the planet as the
//           camera sees it; `tilt` leans it toward the camera and `turn` turns the marker's face
//           away from the camera about the stick (degrees).
//   blur:   Gaussian defocus sigma (px); noise: Gaussian sensor noise sigma (grey levels);
//   gain:   light level (1 = nominal); occlusion: radius of a hand-coloured disc over the planet
//           marker's TR corner, as a fraction of the marker's image size (0 = none).
//   hand:   {"x", "y", "height", "radius"} (m, world frame): a hand-coloured disc of that radius
//           held flat `height` above the table at (x, y), drawn over everything (radius 0: none).
// table: "wood" (soft two-tone shading with a few scraps and strokes), "textured" (the wood under
//         a fine seeded pattern of specks, chips and grain: what plane tracking needs to see) or
//         "plain" (one flat colour: nothing to track).
// "family" is the single markers'; a layout's markers are drawn in the layout's own family.
// Rigid marker sets (marker_layout.hpp) instead of the single markers:
//   "board": a layout file name (relative to the script's folder) or the layout itself: its
//            markers lie on a white sheet on the table, the planet at its planet_centre (moved
//            along z to rest on the sheet at `planet.radius`);
//   "tool_layout": likewise, a tool solid (a cube: faces without markers drawn grey) on a stick
//            that runs from its lowest face to the layout's tip (tool.tip is then the layout's).
// Frames: world = planet marker frame (table plane z = 0, z up); camera frame as OpenCV's.
#include <Eigen/Core>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "tracking/calibration.hpp"
#include "tracking/marker_layout.hpp"
#include "tracking/pose.hpp"

namespace ps::tracking {

struct SynthKey {
  double frame = 0;
  double camDistance = 0.6, camElevationDeg = 50, camAzimuthDeg = -90, camRollDeg = 0;
  // The camera turned away from the planet about its own axes (right, then down): the scene
  // off the image's centre, where a lens distorts most.
  double camPanDeg = 0, camTiltDeg = 0;
  double tipLatDeg = 40, tipLonDeg = -90, tipHeightMm = 20;
  double toolTiltDeg = 20, toolTurnDeg = 0;
  double blur = 0.4, noise = 1.0, gain = 1.0, occlusion = 0.0;
  double handX = 0, handY = 0, handHeight = 0.08, handRadius = 0;
};

struct SynthScript {
  cv::Size size{640, 480};
  double fps = 30;
  std::uint64_t seed = 1;
  std::string family = "tag36h11";
  CameraCalibration camera = syntheticCamera({640, 480});
  int planetId = 0, toolId = 1;
  double planetMarkerSize = 0.08, planetRadius = 0.06, toolMarkerSize = 0.05;
  Eigen::Vector3d tipOffset{0.0, -0.08, 0.0};
  std::shared_ptr<const MarkerLayout> board, toolLayout;  // null: the single markers
  double exposure = 0.0;  // shutter open for this fraction of a frame period (motion blur)
  int motionSamples = 1;
  bool colour = true;
  std::string table = "wood";  // "wood", "textured" or "plain"
  std::vector<SynthKey> keys;

  int frames() const { return keys.empty() ? 0 : int(keys.back().frame) + 1; }
  // Where the planet's centre is in the world (the planet marker's or the board's frame).
  Eigen::Vector3d planetCentre() const;
  // The exact camera of synthetic videos: fx = fy = 0.9375 * width (about 56 degrees across),
  // principal point at the image centre, no distortion.
  static CameraCalibration syntheticCamera(cv::Size size);
  void validate() const;  // InputError naming the field (and key)
};

// Throws core::InputError "SOURCE: ..." for malformed scripts. Layout file names are relative
// to `folder` (a script file's folder).
SynthScript parseSynthScript(const nlohmann::json& j, const std::string& source = "<script>",
                             const std::filesystem::path& folder = {});
SynthScript loadSynthScript(const std::filesystem::path& path);
nlohmann::json toJson(const SynthScript& s);

// Built-in scenes: "demo" (about 10 s: the tool sculpts a few strokes while the camera moves,
// with a lighting change, an occlusion and the tool leaving the frame), "sweep" (the benchmark:
// distances 0.3-0.9 m and tilts up to 60 degrees), "still" (both markers at rest), "short"
// (a few frames, for tests); on the planet board with the tool cube (their layouts read from
// `root`/markers/): "board-demo" (the demo's story with hands over the board), "board-sweep"
// (the tool sweeping over the board), "board-hand" (a hand covering half of it, then all of it
// with the camera still), "board-hidden" (the board fully hidden while the camera stands, then
// moves), "board-covered-move" (on a textured table, the board covered by a hand while the
// camera moves round it), "cube-spin" (the tool cube turned through 360 degrees, edge-on views
// included).
SynthScript builtinScene(const std::string& name, const std::filesystem::path& root = {});
std::vector<std::string> builtinSceneNames();

struct FrameTruth {
  int frame = 0;
  double time = 0;
  Pose camera;        // world -> camera
  Pose planet, tool;  // marker -> camera
  // All four corners inside the image, the face toward the camera, and nothing over it (the
  // tool's card or stick over the planet marker, the hand over either).
  bool planetVisible = false, toolVisible = false;
  bool planetOccluded = false, toolOccluded = false;  // something drawn over the marker
  double planetTiltDeg = 0, toolTiltDeg = 0;  // angle between marker normal and line of sight
  // Boards: each marker's visible fraction (in the image, facing the camera, not covered).
  std::vector<std::pair<int, double>> boardVisible;
  int boardHalfVisible = 0;  // markers at least half visible
  bool cameraStill = false;  // the camera has the previous frame's pose
  Eigen::Vector3d planetCentreCamera = Eigen::Vector3d::Zero();
  Eigen::Vector3d tipCamera = Eigen::Vector3d::Zero();
  Eigen::Vector3d tipPlanet = Eigen::Vector3d::Zero();  // planet frame (m)
  double tipHeight = 0;                                 // above the planet's reference sphere (m)
  nlohmann::json toJson() const;
};

// The pixels (255) where the hand's disc of key k is met before the planet's sphere, seen by
// `camera` (world -> camera): the scene's geometry, the truth a hand mask is measured against.
cv::Mat handInFrontOfPlanet(const SynthScript& s, const SynthKey& k, const Pose& camera);

class SynthRenderer {
 public:
  explicit SynthRenderer(SynthScript script);
  const SynthScript& script() const { return script_; }
  int frames() const { return script_.frames(); }
  FrameTruth truth(double frame) const;
  cv::Mat render(int frame) const;
  // The key frame `frame` is drawn from: its neighbours' values through the smoothstep.
  SynthKey keyAt(double frame) const;

 private:
  void poses(const SynthKey& k, Pose& camera, Pose& tool) const;
  cv::Mat background(const Pose& camera) const;
  // What is drawn over the markers, in pixels: the tool's card and stick, the hand's disc.
  struct Overlays {
    std::vector<cv::Point2d> toolCard, stick;
    bool stickOk = false;
    cv::Point2d disc;
    double discRadius = 0;
  };
  Overlays overlays(const SynthKey& k, const Pose& camera, const Pose& tool) const;
  bool markerInView(const Pose& marker, double size, double& tiltDeg) const;
  void boardTruth(const SynthKey& k, FrameTruth& t) const;
  // The silhouette polygons of what covers the table's markers (tool, stick, hand).
  std::vector<std::vector<cv::Point2d>> occluders(const SynthKey& k, const Pose& camera,
                                                  const Pose& tool) const;
  std::vector<cv::Point2d> handPolygon(const SynthKey& k, const Pose& camera) const;
  void drawBoard(cv::Mat& img, const std::vector<Pose>& cams) const;
  void drawToolSolid(cv::Mat& img, const std::vector<Pose>& tools) const;

  SynthScript script_;
  cv::Mat table_;  // texture of the table (1.2 m square)
  cv::Mat planetCard_, toolCard_;
  std::vector<cv::Mat> boardCards_, toolFaceCards_;
  int planetMargin_ = 2, toolMargin_ = 2;
  // With lens distortion: for each pixel of the frame, where the pinhole image has it.
  cv::Mat distortMapX_, distortMapY_;
};

}  // namespace ps::tracking
