// Intel HEX for the programmer (docs/calibration-blob.md section 8): records 04 (extended
// linear address), 00 (16-byte data) and 01 (EOF) only.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "metro/core/status.hpp"

namespace metro::blob {

// Bytes at consecutive addresses starting at `address`.
struct HexSegment {
  uint32_t address = 0;
  std::vector<uint8_t> bytes;
};

// Writes segments (sorted by address, non-overlapping, each within 32-bit space) as Intel
// HEX: a 04 record before the first data record and whenever the upper 16 address bits
// change, 00 records of at most 16 bytes aligned to 16-byte addresses, then 01. Upper-case
// hex, "\n" line ends. Fails on overlapping or unsorted segments.
Result<std::string> WriteIntelHex(const std::vector<HexSegment>& segments);

// Reads Intel HEX with records 00, 01 and 04 (02, 03 and 05 are refused: the tag's images
// never use them); checks every checksum and the record lengths, requires the EOF record and
// nothing after it. Returns maximal contiguous segments sorted by address. Errors carry the
// file name, the line and the column.
Result<std::vector<HexSegment>> ReadIntelHex(std::string_view text, const std::string& file_name);

// The factory image: `blob` at slot_a and the tombstone word 0x00000000 at slot_b, so that
// `nrfjprog --sectorerase` also erases any old calibration in slot B.
std::vector<HexSegment> FactoryImage(const std::vector<uint8_t>& blob, uint32_t slot_a,
                                     uint32_t slot_b);

// The nrfjprog command line that programs `hex_path` and keeps the other pages.
std::string NrfjprogCommand(const std::string& hex_path);

}  // namespace metro::blob
