// libFuzzer: the stroke journal (io::parseStrokeJournal), the file a crashed live session leaves
// for recovery. Any input must parse or be refused with core::InputError; what parses must
// encode back to the same bytes: the header's fields (its reserved bytes are the writer's to
// fill, under the header's checksum) and every record.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <vector>

#include "core/input_error.hpp"
#include "io/stroke_journal.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    const ps::io::JournalContents j = ps::io::parseStrokeJournal({data, size}, "fuzz.journal");
    std::vector<unsigned char> again = ps::io::encodeJournalHeader(j.base);
    for (const ps::io::JournalRecord& r : j.records) {
      if (r.kind == ps::io::JournalRecordKind::kSaveMark)
        ps::io::encodeJournalMark(r.mark, r.sequence, again);
      else
        ps::io::encodeJournalRecord(r.kind, r.sequence, r.heights, again);
    }
    constexpr std::size_t kFields = 40;  // magic, version, length, side, CRC, radius, generation
    const std::size_t header = ps::io::kStrokeJournalHeaderBytes;
    // An older version's header is read, and written again as the current version (its version
    // field and header checksum differ): only the current version's header must come back.
    const std::uint32_t version = std::uint32_t(data[8]) | std::uint32_t(data[9]) << 8 |
                                  std::uint32_t(data[10]) << 16 | std::uint32_t(data[11]) << 24;
    const bool current = version == ps::io::kStrokeJournalVersion;
    if (again.size() != j.validBytes ||
        (current && !std::equal(again.begin(), again.begin() + kFields, data)) ||
        !std::equal(again.begin() + std::ptrdiff_t(header), again.end(), data + header))
      std::abort();
  } catch (const ps::core::InputError&) {
  }
  return 0;
}
