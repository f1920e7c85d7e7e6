#pragma once
#include <filesystem>
#include <istream>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

namespace ps::replay {

// Where `synth` writes a video's ground truth, and where a replay looks for it.
std::filesystem::path truthPathFor(const std::filesystem::path& video);

// A replay's per-frame log (log.jsonl) against the ground truth of a synthetic recording
// (VIDEO.truth.jsonl), so that replaying a recording with a known truth says how well it was
// tracked: frames the truth says the tool touches and how many of them were sculpted, the
// tool tip's and the planet centre's distance from the truth (median, p95, max; mm) and the
// frames in which the planet was tracked, held and lost against those in which the truth shows
// it. Frames are matched by number; a frame missing from either side is not compared.
struct TruthComparison {
  int frames = 0;    // frames present in both
  int touching = 0;  // truth: the tip within the touch distance, the tool in view
  int sculptedWhenTouching = 0;
  int planetVisible = 0;    // truth: the planet marker (or >= 1 board marker half) in view
  int poseWhenVisible = 0;  // of those, frames with a planet pose
  nlohmann::json tipErrorMm, centreErrorMm;  // {"median", "p95", "max", "frames"} or null
  nlohmann::json toJson() const;
};

// Refuses (core::InputError naming truthName and the line) a truth or log line that is not
// JSON or lacks the fields compared.
TruthComparison compareWithTruth(std::istream& truth, const std::string& truthName,
                                 std::istream& log, const std::string& logName);

}  // namespace ps::replay
