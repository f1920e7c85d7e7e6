#include "replay/session_timeline.hpp"

#include "core/input_error.hpp"

namespace ps::replay {

SettingsControl::SettingsControl(FrameStepper& stepper)
    : stepper_(stepper), s_(SessionSettings::of(stepper.options())) {}

void SettingsControl::apply(const SessionSettings& t) {
  const SessionSettings before = s_;
  try {
    applyParts(t);
  } catch (...) {
    if (writer_) writer_->change(before, s_);  // the sidecar holds what the stepper has
    throw;
  }
  if (writer_) writer_->change(before, s_);
}

void SettingsControl::applyParts(const SessionSettings& t) {
  if (t.spinDeg != s_.spinDeg || t.tiltDeg != s_.tiltDeg) {
    stepper_.setUserRotation(t.rotation());
    s_.spinDeg = t.spinDeg;
    s_.tiltDeg = t.tiltDeg;
  }
  if (t.planetRadius != s_.planetRadius) {
    stepper_.setPlanetSize(t.planetRadius);
    s_.planetRadius = t.planetRadius;
  }
  if (!(t.brush == s_.brush)) {
    stepper_.setBrush(t.brush);
    s_.brush = t.brush;
  }
  if (!(t.displace == s_.displace) || t.pressDepth != s_.pressDepth) {
    stepper_.setDisplacement(t.displace, t.pressDepth);
    s_.displace = t.displace;
    s_.pressDepth = t.pressDepth;
  }
  if (t.tool != s_.tool) {
    stepper_.setTool(t.tool);
    s_.tool = t.tool;
  }
}

void SettingsControl::undo() {
  stepper_.endStroke();
  stepper_.pipeline().undo();
  if (writer_) writer_->event("undo");
}

void SettingsControl::redo() {
  stepper_.endStroke();
  stepper_.pipeline().redo();
  if (writer_) writer_->event("redo");
}

TimelinePlayer::TimelinePlayer(const SessionTimeline& t, SettingsControl& control)
    : t_(t), control_(control) {
  control_.apply(t.settings);
}

void TimelinePlayer::run(const TimelineEntry& e) {
  try {
    if (e.event == "undo")
      control_.undo();
    else if (e.event == "redo")
      control_.redo();
    else
      control_.apply(e.settings);
    ++applied_;
  } catch (const core::InputError& x) {
    warnings_.push_back(t_.path.string() + ":" + std::to_string(e.line) + ": " +
                        (e.event.empty() ? "change" : e.event) + " at frame " +
                        std::to_string(e.frame) + " refused (" + x.what() +
                        "): the replay differs from the session from there on");
  }
}

void TimelinePlayer::before(int frame) {
  while (next_ < t_.entries.size() && t_.entries[next_].frame <= frame) run(t_.entries[next_++]);
}

void TimelinePlayer::finish(int frames) {
  before(frames);
  if (next_ < t_.entries.size())
    warnings_.push_back(t_.path.string() + ":" + std::to_string(t_.entries[next_].line) +
                        ": changes at frame " + std::to_string(t_.entries[next_].frame) +
                        " and later were not applied: the video has only " +
                        std::to_string(frames) + " frames");
}

}  // namespace ps::replay
