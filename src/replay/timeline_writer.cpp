#include "replay/session_timeline.hpp"

#include <cerrno>
#include <cstring>
#include <stdexcept>

namespace ps::replay {

TimelineWriter::~TimelineWriter() {
  close();
}

void TimelineWriter::open(const std::filesystem::path& path, const SessionStart& start,
                          const SessionSettings& settings) {
  close();
  file_ = std::fopen(path.c_str(), "w");
  if (!file_)
    throw std::runtime_error(path.string() + ": cannot write the session sidecar (" +
                             std::strerror(errno) + ")");
  path_ = path;
  frames_ = 0;
  fps_ = start.fps > 0 ? start.fps : 30;
  error_.clear();
  writeLine({{"format", kSessionFormat},
             {"version", kSessionTimelineVersion},
             {"frame", 0},
             {"start", nlohmann::ordered_json(toJson(start))},
             {"settings", nlohmann::ordered_json(toJson(settings))}});
}

void TimelineWriter::close() {
  if (file_) std::fclose(file_);
  file_ = nullptr;
}

void TimelineWriter::writeLine(const nlohmann::ordered_json& j) {
  if (!file_) return;
  const std::string line = j.dump() + "\n";
  // One write and a flush per line: a crash (not a power cut) leaves whole lines only, and at
  // most the last one torn; the reader ignores that one.
  if (std::fwrite(line.data(), 1, line.size(), file_) != line.size() || std::fflush(file_) != 0) {
    error_ = path_.string() + ": cannot write the session sidecar (" + std::strerror(errno) +
             "); stopped writing it";
    close();
  }
}

void TimelineWriter::frameRecorded(double time) {
  if (time != frames_ / fps_) writeLine({{"frame", frames_}, {"time_s", time}});
  ++frames_;
}

void TimelineWriter::change(const SessionSettings& before, const SessionSettings& after) {
  const nlohmann::json d = diff(before, after);
  if (d.empty()) return;
  nlohmann::ordered_json line = {{"frame", frames_}};  // the frame first, for people reading
  for (const auto& [key, value] : d.items()) line[key] = value;
  writeLine(line);
}

void TimelineWriter::event(const std::string& what) {
  writeLine({{"frame", frames_}, {"event", what}});
}

}  // namespace ps::replay
