#pragma once
// The planet board and tool cube rows of `planetsculpt bench track` (bench_track_board.cpp).
#include <functional>
#include <ostream>
#include <string>
#include <vector>

#include "bench/bench.hpp"

namespace ps::bench {

// `bench track`'s options for these rows (`--board-scene`, `--dump`).
struct BoardBenchSettings {
  std::string scene;    // run only this scene ("" = all)
  std::string dumpDir;  // one JSON line per frame in DIR/SCENE.jsonl ("" = none)
  // The detector's expectedSearchEvery (0: the covered board's expected markers ignored, as
  // before; -1: the default).
  int expectedSearchEvery = -1;
  // The detector's expectedSearchDecimate (0: off, every whole-frame search at decimate 2;
  // -1: the default).
  double expectedSearchDecimate = -1;
};

// The board scenes the rows run (--quick leaves board-demo out).
const std::vector<std::string>& boardSceneNames();

// `singleMarkerMs` measures the single-marker default detector's median time per frame on the
// sweep (0: not measured; the ratio is then left out). It is measured again right before each
// scene: this machine's speed drifts by up to 1.5x within minutes (the baseline read 1.85 and
// 2.76 ms in two runs four minutes apart), so a baseline from the start of a run that lasts
// minutes is no baseline for its last scene.
void benchTrackBoards(const BenchOptions& options, const BoardBenchSettings& settings,
                      const std::function<double()>& singleMarkerMs, std::ostream& out);

}  // namespace ps::bench
