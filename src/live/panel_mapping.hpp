#pragma once
// Between the live panel's fields (live/panel.hpp) and the settings they stand for: the command
// line's settings shown at start, and the panel's changes turned into replay::SessionSettings,
// which the session applies and records (replay/session_timeline.hpp).
#include "live/live_app.hpp"
#include "live/panel.hpp"
#include "replay/session_timeline.hpp"

namespace ps::live {

PanelSettings panelFrom(const LiveSettings& s);

// Whether the panel's fields that change what the tool does (replay::SessionSettings) differ.
bool sculptingChanged(const PanelSettings& a, const PanelSettings& b);

// The settings the panel asks for, from those in effect (fields the panel does not show, and
// the brush mode unless raise/lower was toggled, so a `--mode set` session stays in set mode).
replay::SessionSettings panelTarget(const PanelSettings& p, const PanelSettings& applied,
                                    const replay::SessionSettings& now);

}  // namespace ps::live
