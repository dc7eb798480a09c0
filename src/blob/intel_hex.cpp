#include "metro/blob/intel_hex.hpp"

#include <fmt/format.h>

#include <map>

namespace metro::blob {
namespace {

constexpr size_t kDataPerRecord = 16;

std::string Record(uint8_t type, uint16_t address, const uint8_t* data, size_t n) {
  // Checksum: two's complement of the sum of all bytes from the length to the data.
  uint32_t sum = static_cast<uint32_t>(n) + (address >> 8) + (address & 0xFF) + type;
  std::string line = fmt::format(":{:02X}{:04X}{:02X}", n, address, type);
  for (size_t i = 0; i < n; ++i) {
    line += fmt::format("{:02X}", data[i]);
    sum += data[i];
  }
  line += fmt::format("{:02X}\n", (0x100 - (sum & 0xFF)) & 0xFF);
  return line;
}

int HexDigit(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  return -1;
}

}  // namespace

Result<std::string> WriteIntelHex(const std::vector<HexSegment>& segments) {
  std::string out;
  int64_t previous_end = -1;
  int64_t upper = -1;
  for (const auto& seg : segments) {
    const uint64_t end = uint64_t{seg.address} + seg.bytes.size();
    if (end > 0x100000000ull) {
      return MakeError(fmt::format("Intel HEX: segment at 0x{:08X} runs past 4 GiB", seg.address));
    }
    if (static_cast<int64_t>(seg.address) < previous_end) {
      return MakeError(fmt::format(
          "Intel HEX: segment at 0x{:08X} overlaps or precedes the previous one", seg.address));
    }
    previous_end = static_cast<int64_t>(end);
    uint64_t addr = seg.address;
    size_t i = 0;
    while (i < seg.bytes.size()) {
      // At most 16 bytes, up to the next 16-byte boundary (which never crosses 64 KiB).
      const size_t n = std::min(kDataPerRecord - static_cast<size_t>(addr % kDataPerRecord),
                                seg.bytes.size() - i);
      if (static_cast<int64_t>(addr >> 16) != upper) {
        upper = static_cast<int64_t>(addr >> 16);
        const uint8_t ela[2] = {static_cast<uint8_t>(upper >> 8), static_cast<uint8_t>(upper)};
        out += Record(0x04, 0, ela, 2);
      }
      out += Record(0x00, static_cast<uint16_t>(addr & 0xFFFF), seg.bytes.data() + i, n);
      addr += n;
      i += n;
    }
  }
  out += Record(0x01, 0, nullptr, 0);
  return out;
}

Result<std::vector<HexSegment>> ReadIntelHex(std::string_view text, const std::string& file) {
  std::map<uint32_t, uint8_t> bytes;
  uint32_t upper = 0;
  bool eof = false;
  int64_t line_no = 0;
  size_t pos = 0;
  while (pos < text.size()) {
    size_t nl = text.find('\n', pos);
    if (nl == std::string_view::npos) nl = text.size();
    std::string_view line = text.substr(pos, nl - pos);
    pos = nl + 1;
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    if (line.empty()) continue;
    if (eof) return MakeError(file, line_no, 1, "Intel HEX: record after the EOF record");
    if (line[0] != ':') {
      return MakeError(file, line_no, 1, "Intel HEX: expected ':' at the start of a record");
    }
    if (line.size() < 11 || (line.size() - 1) % 2 != 0) {
      return MakeError(file, line_no, 1,
                       "Intel HEX: a record is ':' and an even number (>= 10) of hex digits");
    }
    std::vector<uint8_t> rec;
    for (size_t i = 1; i < line.size(); i += 2) {
      const int hi = HexDigit(line[i]);
      const int lo = HexDigit(line[i + 1]);
      if (hi < 0 || lo < 0) {
        return MakeError(file, line_no, static_cast<int64_t>(hi < 0 ? i + 1 : i + 2),
                         "Intel HEX: expected a hex digit");
      }
      rec.push_back(static_cast<uint8_t>(hi * 16 + lo));
    }
    const size_t n = rec[0];
    if (rec.size() != n + 5) {
      return MakeError(file, line_no, 2,
                       fmt::format("Intel HEX: length field says {} data bytes, the record "
                                   "holds {}",
                                   n, rec.size() - 5));
    }
    uint32_t sum = 0;
    for (uint8_t b : rec) sum += b;
    if ((sum & 0xFF) != 0) {
      return MakeError(file, line_no, static_cast<int64_t>(line.size() - 1),
                       fmt::format("Intel HEX: checksum 0x{:02X} is wrong, expected 0x{:02X}",
                                   rec.back(), (0x100 - ((sum - rec.back()) & 0xFF)) & 0xFF));
    }
    const uint16_t offset = static_cast<uint16_t>(rec[1] << 8 | rec[2]);
    const uint8_t type = rec[3];
    if (type == 0x00) {
      for (size_t i = 0; i < n; ++i) {
        const uint64_t a = (uint64_t{upper} << 16) + offset + i;
        if (a > 0xFFFFFFFFull) {
          return MakeError(file, line_no, 4, "Intel HEX: data past the 4 GiB address space");
        }
        if (!bytes.emplace(static_cast<uint32_t>(a), rec[4 + i]).second) {
          return MakeError(file, line_no, 4,
                           fmt::format("Intel HEX: address 0x{:08X} is written twice", a));
        }
      }
    } else if (type == 0x01) {
      if (n != 0) return MakeError(file, line_no, 2, "Intel HEX: EOF record with data");
      eof = true;
    } else if (type == 0x04) {
      if (n != 2) {
        return MakeError(file, line_no, 2, "Intel HEX: extended linear address needs 2 bytes");
      }
      upper = static_cast<uint32_t>(rec[4] << 8 | rec[5]);
    } else {
      return MakeError(file, line_no, 8,
                       fmt::format("Intel HEX: record type {:02X} is not supported (only 00, 01 "
                                   "and 04)",
                                   type));
    }
  }
  if (!eof) return MakeError(file, line_no, 0, "Intel HEX: missing EOF record (:00000001FF)");
  std::vector<HexSegment> out;
  for (const auto& [addr, value] : bytes) {
    if (out.empty() || uint64_t{out.back().address} + out.back().bytes.size() != addr) {
      out.push_back(HexSegment{addr, {}});
    }
    out.back().bytes.push_back(value);
  }
  return out;
}

std::vector<HexSegment> FactoryImage(const std::vector<uint8_t>& blob, uint32_t slot_a,
                                     uint32_t slot_b) {
  std::vector<HexSegment> segs = {HexSegment{slot_a, blob}, HexSegment{slot_b, {0, 0, 0, 0}}};
  if (slot_b < slot_a) std::swap(segs[0], segs[1]);
  return segs;
}

std::string NrfjprogCommand(const std::string& hex_path) {
  return fmt::format("nrfjprog -f NRF51 --program {} --sectorerase --verify --reset", hex_path);
}

}  // namespace metro::blob
