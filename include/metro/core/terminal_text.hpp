// Text from data made safe for a terminal or a log line.
//
// File names, CSV header names, tag-registry names and blob metadata are bytes chosen by
// whoever wrote the file. Printed raw they can move the cursor, retitle the window, hide
// text (ESC and OSC sequences) or forge a line of their own (a newline). Every string that
// reaches stderr or stdout as text passes through one of these (apps/unix_cli.hpp does it
// for errors, notes and tables).
#pragma once

#include <string>
#include <string_view>

namespace metro {

// `text` with every control character written as an escape: "\n", "\r", "\t", other C0
// controls and DEL as "\x1b" (two lower-case hex digits), the C1 controls U+0080..U+009F
// (UTF-8 C2 80..C2 9F) as "\u009b", and bytes that are not UTF-8 as "\xff". Printable
// ASCII and valid UTF-8 pass unchanged; a backslash is not doubled (this is for reading,
// not a reversible encoding). Escaping twice changes nothing more.
inline std::string EscapeControlChars(std::string_view text);

// The same for text the program laid out in lines itself (a table, a report): "\n" and
// "\t" are kept, everything else is escaped as above.
inline std::string EscapeControlCharsKeepLines(std::string_view text);

namespace internal {

inline std::string EscapeControl(std::string_view text, bool keep_lines) {
  static const char kHex[] = "0123456789abcdef";
  std::string out;
  out.reserve(text.size());
  auto hex_byte = [&out](unsigned char c) {
    out += "\\x";
    out += kHex[c >> 4];
    out += kHex[c & 0xF];
  };
  const size_t n = text.size();
  for (size_t i = 0; i < n;) {
    const auto c = static_cast<unsigned char>(text[i]);
    if (c < 0x80) {
      if (c == '\n' && keep_lines) {
        out += '\n';
      } else if (c == '\t' && keep_lines) {
        out += '\t';
      } else if (c == '\n') {
        out += "\\n";
      } else if (c == '\r') {
        out += "\\r";
      } else if (c == '\t') {
        out += "\\t";
      } else if (c < 0x20 || c == 0x7F) {
        hex_byte(c);
      } else {
        out += static_cast<char>(c);
      }
      ++i;
      continue;
    }
    // A UTF-8 sequence: its length from the lead byte, then continuation bytes 10xxxxxx.
    size_t len = c >= 0xF0 && c <= 0xF4 ? 4 : c >= 0xE0 ? 3 : c >= 0xC2 && c <= 0xDF ? 2 : 0;
    if (c >= 0xF5) len = 0;
    bool valid = len > 0 && i + len <= n;
    for (size_t k = 1; valid && k < len; ++k) {
      valid = (static_cast<unsigned char>(text[i + k]) & 0xC0) == 0x80;
    }
    if (valid && len == 3) {
      const auto c1 = static_cast<unsigned char>(text[i + 1]);
      valid = !(c == 0xE0 && c1 < 0xA0) && !(c == 0xED && c1 >= 0xA0);  // Overlong, surrogate.
    } else if (valid && len == 4) {
      const auto c1 = static_cast<unsigned char>(text[i + 1]);
      valid = !(c == 0xF0 && c1 < 0x90) && !(c == 0xF4 && c1 >= 0x90);  // Overlong, > U+10FFFF.
    }
    if (!valid) {
      hex_byte(c);
      ++i;
      continue;
    }
    const auto c1 = static_cast<unsigned char>(text[i + 1]);
    if (c == 0xC2 && c1 <= 0x9F) {  // C1 control U+0080..U+009F (0x9B is CSI).
      out += "\\u00";
      out += kHex[c1 >> 4];
      out += kHex[c1 & 0xF];
    } else {
      out.append(text.data() + i, len);
    }
    i += len;
  }
  return out;
}

}  // namespace internal

inline std::string EscapeControlChars(std::string_view text) {
  return internal::EscapeControl(text, false);
}

inline std::string EscapeControlCharsKeepLines(std::string_view text) {
  return internal::EscapeControl(text, true);
}

}  // namespace metro
