#pragma once
// The replay options the bundled demo recording (data/demo.mkv) is tracked with: the planet
// board and the tool cube committed in markers/, as `planetsculpt demo` uses by default.
#include <memory>

#include "app/build_paths.hpp"
#include "replay/replay.hpp"
#include "tracking/marker_layout.hpp"

namespace ps::bench {

inline replay::ReplayOptions demoReplayOptions() {
  replay::ReplayOptions o;
  const auto root = app::sourceDir();
  o.scene.useBoard(std::make_shared<const tracking::MarkerLayout>(
      tracking::loadMarkerLayout(tracking::defaultBoardPath(root))));
  o.scene.useToolLayout(std::make_shared<const tracking::MarkerLayout>(
      tracking::loadMarkerLayout(tracking::defaultToolLayoutPath(root))));
  return o;
}

}  // namespace ps::bench
