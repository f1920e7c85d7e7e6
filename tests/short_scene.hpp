#pragma once
// The built-in synthetic "short" scene (12 frames at 320x240, grey) as a lossless video written
// once per test process, and the replay options and camera that match it. Shared by the replay
// and frame-stepper tests.
#include <unistd.h>

#include <filesystem>
#include <string>

#include "fresh_dir.hpp"
#include "replay/replay.hpp"
#include "tracking/synth.hpp"
#include "tracking/video.hpp"

namespace ps::testkit {

inline std::filesystem::path shortSceneDir() {
  static const std::filesystem::path d = freshDir("short_scene");
  return d;
}

inline const std::filesystem::path& shortSceneVideo() {
  static const std::filesystem::path path = [] {
    const auto p = shortSceneDir() / "short.mkv";
    auto script = tracking::builtinScene("short");
    script.colour = false;
    const tracking::SynthRenderer r(script);
    tracking::LosslessWriter w(p, script.size, script.fps, false);
    for (int f = 0; f < r.frames(); ++f) w.write(r.render(f));
    w.close();
    return p;
  }();
  return path;
}

inline replay::ReplayOptions shortSceneOptions() {
  replay::ReplayOptions o;
  const auto s = tracking::builtinScene("short");
  o.scene.planet.size = s.planetMarkerSize;
  o.scene.tool.size = s.toolMarkerSize;
  o.scene.planetRadius = s.planetRadius;
  o.scene.tipOffset = s.tipOffset;
  return o;
}

inline tracking::CameraCalibration shortSceneCamera() {
  return tracking::SynthScript::syntheticCamera({320, 240});
}

}  // namespace ps::testkit
