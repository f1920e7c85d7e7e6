#pragma once
#include <array>
#include <cstddef>
#include <string>
#include <string_view>

#include "core/input_error.hpp"

namespace ps::core {

// One spelling of an enum value on the command line, in settings files and in logs.
template <typename E>
struct NamedValue {
  E value;
  const char* name;
};

// The names of an enum's values, written once so that printing and parsing cannot disagree and
// every refusal lists the same choices. The first entry of a value is its name; later entries
// of the same value are aliases, accepted when parsing and never printed.
template <typename E, std::size_t N>
struct NameTable {
  const char* what;  // "brush mode": how a refusal names the setting
  std::array<NamedValue<E>, N> entries;

  bool contains(E value) const {
    for (const NamedValue<E>& e : entries)
      if (e.value == value) return true;
    return false;
  }

  // "?" for a value with no entry (a corrupt enum), so that a log line is still written.
  const char* nameOf(E value) const {
    for (const NamedValue<E>& e : entries)
      if (e.value == value) return e.name;
    return "?";
  }

  E parse(std::string_view text) const {
    for (const NamedValue<E>& e : entries)
      if (text == e.name) return e.value;
    throw InputError(std::string(what) + " '" + std::string(text) + "' is not one of " + choices());
  }

  // The names (aliases left out), comma separated, for help texts and refusals.
  std::string choices() const {
    std::string out;
    for (std::size_t i = 0; i < N; ++i) {
      if (isAlias(i)) continue;
      if (!out.empty()) out += ", ";
      out += entries[i].name;
    }
    return out;
  }

 private:
  bool isAlias(std::size_t i) const {
    for (std::size_t j = 0; j < i; ++j)
      if (entries[j].value == entries[i].value) return true;
    return false;
  }
};

}  // namespace ps::core
