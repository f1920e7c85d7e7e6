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

// A number with `digits` significant digits (printf's %.*g), for messages and notes that name a
// value: 17 reads back exactly (exactNumber); fewer where the value is a reading, not a key.
inline std::string formatNumber(double x, int digits) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.*g", digits, x);
  return buf;
}

// A number as it reads back exactly (17 significant digits), for messages that name a value.
inline std::string exactNumber(double x) {
  return formatNumber(x, 17);
}

}  // namespace ps::core
