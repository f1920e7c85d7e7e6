#pragma once
// The headless OpenGL context a rendering benchmark needs, or the row that says why it was
// skipped (no EGL here): the benchmark returns when this gives nothing.
#include <memory>
#include <nlohmann/json.hpp>
#include <ostream>
#include <string>

#include "render/egl_context.hpp"

namespace ps::bench {

inline std::unique_ptr<render::EglContext> glContextOrSkip(const char* bench, std::ostream& out,
                                                           const nlohmann::json& extra = {}) {
  try {
    return std::make_unique<render::EglContext>();
  } catch (const std::exception& e) {
    nlohmann::json row = {{"bench", bench},
                          {"skipped", true},
                          {"reason", std::string("no headless OpenGL: ") + e.what()}};
    for (const auto& [k, v] : extra.items()) row[k] = v;
    out << row.dump() << std::endl;
    return nullptr;
  }
}

}  // namespace ps::bench
