#pragma once
// The shape of the JSON fuzz targets: any JSON must parse or be refused with core::InputError;
// what parses writes back (toJson) to JSON that parses to the same JSON. Anything else aborts.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <nlohmann/json.hpp>

#include "core/input_error.hpp"

namespace ps::fuzz {

template <class Parse, class ToJson>
int jsonRoundTrip(const std::uint8_t* data, std::size_t size, Parse parse, ToJson toJson) {
  const nlohmann::json j = nlohmann::json::parse(data, data + size, nullptr, false);
  if (j.is_discarded()) return 0;
  nlohmann::json once;
  try {
    once = toJson(parse(j, "fuzz.json"));
  } catch (const core::InputError&) {
    return 0;
  }
  try {
    if (toJson(parse(once, "again.json")) != once) std::abort();
  } catch (const core::InputError&) {
    std::abort();  // what we wrote must read back
  }
  return 0;
}

}  // namespace ps::fuzz
