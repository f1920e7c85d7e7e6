// libFuzzer: the stroke journal (io::parseStrokeJournal), the file a crashed live session leaves
// for recovery. Any input must parse or be refused with core::InputError; what parses must
// encode back to the same bytes, record by record.
#include <cstddef>
#include <cstdint>
#include <algorithm>
#include <cstdlib>
#include <vector>

#include "core/input_error.hpp"
#include "io/stroke_journal.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    const ps::io::JournalContents j = ps::io::parseStrokeJournal({data, size}, "fuzz.journal");
    std::vector<unsigned char> again = ps::io::encodeJournalHeader(j.base);
    for (const ps::io::JournalRecord& r : j.records)
      ps::io::encodeJournalRecord(r.kind, r.sequence, r.heights, again);
    if (again.size() != j.validBytes || !std::equal(again.begin(), again.end(), data)) std::abort();
  } catch (const ps::core::InputError&) {
  }
  return 0;
}
