#pragma once
#include <cstdio>
#include <stdexcept>
#include <string>

namespace ps::core {

// Thrown for anything a user handed us that we refuse: the message names the value and why.
class InputError : public std::invalid_argument {
 public:
  explicit InputError(const std::string& what) : std::invalid_argument(what) {}
};

// A number as it reads back exactly (17 significant digits), for messages that name a value.
inline std::string exactNumber(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.17g", x);
  return buf;
}

}  // namespace ps::core
