#pragma once
// The message of the core::InputError a piece of code throws ("" when it throws none): the tests
// of bad input compare it with what the user should read.
#include <functional>
#include <string>

#include "core/input_error.hpp"

namespace ps::testkit {

inline std::string errorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const core::InputError& e) {
    return e.what();
  }
  return "";
}

}  // namespace ps::testkit
