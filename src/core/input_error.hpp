#pragma once
#include <stdexcept>
#include <string>

namespace ps::core {

// Thrown for anything a user handed us that we refuse: the message names the value and why.
class InputError : public std::invalid_argument {
 public:
  explicit InputError(const std::string& what) : std::invalid_argument(what) {}
};

}  // namespace ps::core
