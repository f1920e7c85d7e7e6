#include "edit/stroke_script.hpp"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <numbers>
#include <sstream>

#include "core/input_error.hpp"
#include "edit/control_vertex.hpp"

namespace ps::edit {

namespace {

[[noreturn]] void fail(const std::string& source, int line, const std::string& what) {
  throw core::InputError(source + ":" + std::to_string(line) + ": " + what);
}

// Runs f; an InputError it throws gets "SOURCE:LINE: " in front.
template <class F>
void at(const std::string& source, int line, F&& f) {
  try {
    f();
  } catch (const core::InputError& e) {
    fail(source, line, e.what());
  }
}

double parseNumber(std::string_view token, const std::string& what) {
  double x = 0;
  const char* b = token.data();
  const char* e = b + token.size();
  if (!token.empty() && *b == '+') ++b;
  const auto [ptr, ec] = std::from_chars(b, e, x);
  if (ec != std::errc() || ptr != e || b == e) {
    throw core::InputError(what + " '" + std::string(token) + "' is not a number");
  }
  return x;
}

int parseCount(std::string_view token, const std::string& what) {
  int n = 0;
  const auto [ptr, ec] = std::from_chars(token.data(), token.data() + token.size(), n);
  if (ec != std::errc() || ptr != token.data() + token.size() || n < 1) {
    throw core::InputError(what + " '" + std::string(token) + "' is not a positive whole number");
  }
  return n;
}

std::vector<std::string_view> tokens(std::string_view line) {
  std::vector<std::string_view> out;
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t' || line[i] == '\r')) ++i;
    std::size_t j = i;
    while (j < line.size() && line[j] != ' ' && line[j] != '\t' && line[j] != '\r') ++j;
    if (j > i) out.push_back(line.substr(i, j - i));
    i = j;
  }
  return out;
}

// POINT [dt=S] from tokens[1..].
void parsePointAndDt(const std::vector<std::string_view>& t, ScriptCommand& c) {
  const std::string cmd(t[0]);
  std::size_t i = 1;
  if (i < t.size() && t[i].substr(0, 4) == "xyz=") {
    const std::string_view list = t[i].substr(4);
    double xyz[3];
    std::size_t start = 0;
    for (int k = 0; k < 3; ++k) {
      const std::size_t comma = k < 2 ? list.find(',', start) : list.size();
      if (comma == std::string_view::npos) {
        throw core::InputError(cmd + ": xyz='" + std::string(list) +
                               "' needs three comma-separated numbers X,Y,Z");
      }
      xyz[k] = parseNumber(list.substr(start, comma - start), cmd + " coordinate");
      start = comma + 1;
    }
    c.point.xyz = true;
    c.point.value = {xyz[0], xyz[1], xyz[2]};
    ++i;
  } else {
    if (t.size() < 3 || t[1].find('=') != std::string_view::npos ||
        t[2].find('=') != std::string_view::npos) {
      throw core::InputError(cmd + " needs a point: LAT LON in degrees or xyz=X,Y,Z in metres");
    }
    c.point.xyz = false;
    c.point.value = {parseNumber(t[1], cmd + " latitude"), parseNumber(t[2], cmd + " longitude"),
                     0.0};
    i = 3;
  }
  for (; i < t.size(); ++i) {
    if (t[i].substr(0, 3) == "dt=") {
      c.dt = parseNumber(t[i].substr(3), cmd + " dt");
    } else {
      throw core::InputError(cmd + ": unexpected '" + std::string(t[i]) +
                             "' (expected dt=SECONDS)");
    }
  }
}

void parseBrush(const std::vector<std::string_view>& t, BrushSettings& b) {
  if (t.size() < 2) throw core::InputError("brush needs at least one KEY=VALUE");
  for (std::size_t i = 1; i < t.size(); ++i) {
    const std::size_t eq = t[i].find('=');
    if (eq == std::string_view::npos || eq == 0 || eq + 1 == t[i].size()) {
      throw core::InputError("brush: '" + std::string(t[i]) + "' is not KEY=VALUE");
    }
    const std::string key(t[i].substr(0, eq));
    const std::string_view value = t[i].substr(eq + 1);
    if (key == "r_km") {
      b.radius = 1000.0 * parseNumber(value, "r_km");
    } else if (key == "r_m") {
      b.radius = parseNumber(value, "r_m");
    } else if (key == "sigma") {
      b.sigma = parseNumber(value, "sigma");
    } else if (key == "mu") {
      b.mu = parseNumber(value, "mu");
    } else if (key == "mode") {
      b.mode = brushModeFromString(std::string(value));
    } else if (key == "strength_m") {
      b.strength = parseNumber(value, "strength_m");
      b.rate = false;
    } else if (key == "rate_mps") {
      b.strength = parseNumber(value, "rate_mps");
      b.rate = true;
    } else if (key == "target_m") {
      b.target = parseNumber(value, "target_m");
    } else if (key == "spacing") {
      b.spacing = parseNumber(value, "spacing");
    } else {
      throw core::InputError(
          "brush: unknown key '" + key +
          "' (expected r_km, r_m, sigma, mu, mode, strength_m, rate_mps, target_m, spacing)");
    }
  }
  b.validate();
}

std::string pointText(const ScriptPoint& p) {
  if (p.xyz)
    return "xyz=" + core::exactNumber(p.value.x()) + "," + core::exactNumber(p.value.y()) + "," +
           core::exactNumber(p.value.z());
  return core::exactNumber(p.value.x()) + " " + core::exactNumber(p.value.y());
}

std::string brushText(const BrushSettings& b) {
  std::string s = "brush r_m=" + core::exactNumber(b.radius) +
                  " sigma=" + core::exactNumber(b.sigma) + " mu=" + core::exactNumber(b.mu) +
                  " mode=" + toString(b.mode) + (b.rate ? " rate_mps=" : " strength_m=") +
                  core::exactNumber(b.strength);
  s += " target_m=" + core::exactNumber(b.target) + " spacing=" + core::exactNumber(b.spacing);
  return s;
}

void checkPoint(const ScriptCommand& c, const core::Chart& chart) {
  if (!std::isfinite(c.dt) || c.dt < 0.0)
    throw core::InputError("dt = " + core::exactNumber(c.dt) + " s must be finite and >= 0");
  if (c.point.xyz) {
    (void)nearestVertex(chart, c.point.value);  // throws for non-finite or the centre
    return;
  }
  // LAT LON is a direction on the reference sphere: a chart that is no sphere (a torus, a
  // cylinder, the flat grid: sphereRadius() 0) would put every such point at the origin.
  if (!(chart.sphereRadius() > 0.0)) {
    throw core::InputError("a LAT LON point needs a sphere, and this planet's " + chart.name() +
                           " chart is none: give the point as xyz=X,Y,Z (metres)");
  }
  const double lat = c.point.value.x(), lon = c.point.value.y();
  if (!std::isfinite(lat) || lat < -90.0 || lat > 90.0) {
    throw core::InputError("latitude " + core::exactNumber(lat) + " degrees is outside [-90, 90]");
  }
  if (!std::isfinite(lon) || lon < -360.0 || lon > 360.0) {
    throw core::InputError("longitude " + core::exactNumber(lon) +
                           " degrees is outside [-360, 360]");
  }
}

}  // namespace

std::string StrokeScript::toText() const {
  std::ostringstream os;
  for (const ScriptCommand& c : commands) {
    switch (c.kind) {
      case ScriptCommand::Kind::kBrush:
        os << brushText(c.brush);
        break;
      case ScriptCommand::Kind::kStamp:
        os << "stamp " << pointText(c.point);
        break;
      case ScriptCommand::Kind::kStroke:
        os << "stroke " << pointText(c.point);
        break;
      case ScriptCommand::Kind::kTo:
        os << "to " << pointText(c.point);
        break;
      case ScriptCommand::Kind::kEnd:
        os << "end";
        break;
      case ScriptCommand::Kind::kUndo:
        os << "undo " << c.count;
        break;
      case ScriptCommand::Kind::kRedo:
        os << "redo " << c.count;
        break;
    }
    const bool hasPoint = c.kind == ScriptCommand::Kind::kStamp ||
                          c.kind == ScriptCommand::Kind::kStroke ||
                          c.kind == ScriptCommand::Kind::kTo;
    if (hasPoint && c.dt != 0.0) os << " dt=" << core::exactNumber(c.dt);
    os << "\n";
  }
  return os.str();
}

StrokeScript parseStrokeScript(std::string_view text, const std::string& source) {
  StrokeScript script;
  script.source = source;
  BrushSettings brush;
  int lineNo = 0;
  std::size_t pos = 0;
  while (pos <= text.size()) {
    std::size_t eol = text.find('\n', pos);
    if (eol == std::string_view::npos) eol = text.size();
    std::string_view line = text.substr(pos, eol - pos);
    pos = eol + 1;
    ++lineNo;
    const std::size_t hash = line.find('#');
    if (hash != std::string_view::npos) line = line.substr(0, hash);
    const auto t = tokens(line);
    if (t.empty()) {
      if (eol == text.size()) break;
      continue;
    }
    ScriptCommand c;
    c.line = lineNo;
    const std::string cmd(t[0]);
    at(source, lineNo, [&] {
      if (cmd == "brush") {
        c.kind = ScriptCommand::Kind::kBrush;
        parseBrush(t, brush);
        c.brush = brush;
      } else if (cmd == "stamp" || cmd == "stroke" || cmd == "to") {
        c.kind = cmd == "stamp"    ? ScriptCommand::Kind::kStamp
                 : cmd == "stroke" ? ScriptCommand::Kind::kStroke
                                   : ScriptCommand::Kind::kTo;
        parsePointAndDt(t, c);
      } else if (cmd == "end") {
        c.kind = ScriptCommand::Kind::kEnd;
        if (t.size() > 1)
          throw core::InputError("end takes no arguments, got '" + std::string(t[1]) + "'");
      } else if (cmd == "undo" || cmd == "redo") {
        c.kind = cmd == "undo" ? ScriptCommand::Kind::kUndo : ScriptCommand::Kind::kRedo;
        if (t.size() > 2)
          throw core::InputError(cmd + " takes at most one count, got '" + std::string(t[2]) + "'");
        if (t.size() == 2) c.count = parseCount(t[1], cmd + " count");
      } else {
        throw core::InputError("unknown command '" + cmd +
                               "' (expected brush, stamp, stroke, to, end, undo, redo)");
      }
    });
    script.commands.push_back(c);
    if (eol == text.size()) break;
  }
  return script;
}

StrokeScript loadStrokeScript(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw core::InputError("cannot read stroke file '" + path.string() + "'");
  std::ostringstream os;
  os << in.rdbuf();
  return parseStrokeScript(os.str(), path.string());
}

Eigen::Vector3d scriptPosition(const ScriptPoint& p, double radius) {
  if (p.xyz) return p.value;
  const double lat = p.value.x() * std::numbers::pi / 180.0,
               lon = p.value.y() * std::numbers::pi / 180.0;
  return radius * Eigen::Vector3d(std::cos(lon) * std::cos(lat), std::sin(lon) * std::cos(lat),
                                  std::sin(lat));
}

void validateStrokeScript(const StrokeScript& script, const EditPipeline& pipeline) {
  const std::string& src = script.source;
  if (pipeline.inStroke())
    fail(src, script.commands.empty() ? 0 : script.commands.front().line,
         "a stroke is already open");
  const core::Chart& chart = pipeline.terrain().chart();
  const bool undo = pipeline.undoEnabled();
  std::size_t undoable = undo ? pipeline.journal().undoCount() : 0;
  std::size_t redoable = undo ? pipeline.journal().redoCount() : 0;
  int strokeLine = 0;  // 0: no stroke open
  for (const ScriptCommand& c : script.commands) {
    at(src, c.line, [&] {
      using K = ScriptCommand::Kind;
      switch (c.kind) {
        case K::kBrush:
          if (strokeLine) {
            throw core::InputError("the brush cannot change inside a stroke (begun on line " +
                                   std::to_string(strokeLine) + ")");
          }
          c.brush.validate();
          break;
        case K::kStamp:
        case K::kStroke:
          if (strokeLine) {
            throw core::InputError(std::string(c.kind == K::kStamp ? "stamp" : "stroke") +
                                   " inside a stroke (begun on line " + std::to_string(strokeLine) +
                                   "): 'end' it first");
          }
          checkPoint(c, chart);
          if (c.kind == K::kStroke) {
            strokeLine = c.line;
          } else {
            ++undoable, redoable = 0;
          }
          break;
        case K::kTo:
          if (!strokeLine)
            throw core::InputError("'to' outside a stroke: begin one with 'stroke LAT LON'");
          checkPoint(c, chart);
          break;
        case K::kEnd:
          if (!strokeLine) throw core::InputError("'end' without a stroke");
          strokeLine = 0;
          ++undoable, redoable = 0;
          break;
        case K::kUndo:
        case K::kRedo: {
          const bool isUndo = c.kind == K::kUndo;
          const std::string name = isUndo ? "undo" : "redo";
          if (strokeLine)
            throw core::InputError(name + " inside a stroke (begun on line " +
                                   std::to_string(strokeLine) + ")");
          if (!undo) throw core::InputError(name + " needs the undo journal, which is disabled");
          std::size_t& have = isUndo ? undoable : redoable;
          if (std::size_t(c.count) > have) {
            throw core::InputError(name + " " + std::to_string(c.count) + ": only " +
                                   std::to_string(have) + " step(s) can be " +
                                   (isUndo ? "undone" : "redone") + " here");
          }
          have -= std::size_t(c.count);
          (isUndo ? redoable : undoable) += std::size_t(c.count);
          break;
        }
      }
    });
  }
  if (strokeLine) fail(src, strokeLine, "this stroke is never ended (add 'end')");
}

ScriptRunReport runStrokeScript(const StrokeScript& script, EditPipeline& pipeline) {
  validateStrokeScript(script, pipeline);
  ScriptRunReport rep;
  GaussianBrush brush;
  const double radius = pipeline.terrain().chart().sphereRadius();
  // Undo steps the script relies on must not be forgotten mid-run.
  UndoJournal& journal = pipeline.journal();
  const std::size_t cap = journal.maxBytes();
  journal.setMaxBytes(std::size_t(-1));
  try {
    for (const ScriptCommand& c : script.commands) {
      using K = ScriptCommand::Kind;
      const ToolInput in{scriptPosition(c.point, radius), c.dt};  // used by stamp, stroke, to
      switch (c.kind) {
        case K::kBrush:
          brush.setSettings(c.brush);
          break;
        case K::kStamp:
          rep.edits.add(pipeline.apply(brush, in));
          ++rep.strokes;
          break;
        case K::kStroke:
          rep.edits.add(pipeline.beginStroke(brush, in));
          break;
        case K::kTo:
          rep.edits.add(pipeline.moveTo(in));
          break;
        case K::kEnd:
          pipeline.endStroke();
          ++rep.strokes;
          break;
        case K::kUndo:
          for (int i = 0; i < c.count; ++i) pipeline.undo();
          rep.undos += c.count;
          break;
        case K::kRedo:
          for (int i = 0; i < c.count; ++i) pipeline.redo();
          rep.redos += c.count;
          break;
      }
    }
  } catch (...) {
    journal.setMaxBytes(cap);
    throw;
  }
  journal.setMaxBytes(cap);
  return rep;
}

// ---------------------------------------------------------------------------------------------

void StrokeRecorder::clear() {
  script_.commands.clear();
  haveBrush_ = false;
  open_ = false;
  moved_ = false;
}

void StrokeRecorder::push(ScriptCommand c) {
  c.line = int(script_.commands.size()) + 1;
  script_.commands.push_back(c);
}

void StrokeRecorder::onBeginStroke(const Tool& tool, const ToolInput& start) {
  const auto* brush = dynamic_cast<const GaussianBrush*>(&tool);
  if (!brush)
    throw core::InputError("tool '" + tool.name() + "' cannot be recorded in a stroke script");
  if (!haveBrush_ || !(brush->settings() == brush_)) {
    ScriptCommand b;
    b.kind = ScriptCommand::Kind::kBrush;
    b.brush = brush->settings();
    push(b);
    brush_ = brush->settings();
    haveBrush_ = true;
  }
  ScriptCommand c;
  c.kind = ScriptCommand::Kind::kStroke;
  c.point = {true, start.position};
  c.dt = start.dt;
  openIndex_ = script_.commands.size();
  push(c);
  open_ = true;
  moved_ = false;
}

void StrokeRecorder::onMoveStroke(const ToolInput& sample) {
  ScriptCommand c;
  c.kind = ScriptCommand::Kind::kTo;
  c.point = {true, sample.position};
  c.dt = sample.dt;
  push(c);
  moved_ = true;
}

void StrokeRecorder::onEndStroke() {
  if (open_ && !moved_) {
    script_.commands[openIndex_].kind = ScriptCommand::Kind::kStamp;
  } else {
    ScriptCommand c;
    c.kind = ScriptCommand::Kind::kEnd;
    push(c);
  }
  open_ = false;
}

void StrokeRecorder::onUndo() {
  ScriptCommand c;
  c.kind = ScriptCommand::Kind::kUndo;
  push(c);
}

void StrokeRecorder::onRedo() {
  ScriptCommand c;
  c.kind = ScriptCommand::Kind::kRedo;
  push(c);
}

}  // namespace ps::edit
