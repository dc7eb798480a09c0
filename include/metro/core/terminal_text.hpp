// Text from data made safe for a terminal or a log line.
//
// File names, CSV header names, tag-registry names and blob metadata are bytes chosen by
// whoever wrote the file. Printed raw they can move the cursor, retitle the window, hide
// text (ESC and OSC sequences) or forge a line of their own (a newline). Every string that
// reaches stderr or stdout as text passes through one of these (apps/unix_cli.hpp does it
// for errors, notes and tables).
#pragma once

#include <algorithm>
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

// At most `width` bytes of `text` around byte `at` (0-based; npos or past the end: from the
// start), "..." where it was cut, control characters escaped (EscapeControlChars): how a
// message quotes a long input, once, on one line (a 1 MB model is quoted by the 120 bytes
// around its error). The cut keeps UTF-8 sequences whole; `at` lies about a third into the
// window, so the text before the error and after it both show.
inline std::string Excerpt(std::string_view text, size_t at = std::string_view::npos,
                           size_t width = 120);

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

inline std::string Excerpt(std::string_view text, size_t at, size_t width) {
  if (text.size() <= width) return EscapeControlChars(text);
  if (at >= text.size()) at = 0;
  size_t begin = at > width / 3 ? at - width / 3 : 0;
  size_t end = std::min(text.size(), begin + width);
  begin = end - width;  // A window that ends at the text's end still holds `width` bytes.
  auto continuation = [&text](size_t i) {
    return i < text.size() && (static_cast<unsigned char>(text[i]) & 0xC0) == 0x80;
  };
  while (begin > 0 && continuation(begin)) --begin;  // Start at a sequence's lead byte.
  while (end < text.size() && continuation(end)) --end;
  return (begin > 0 ? "..." : "") + EscapeControlChars(text.substr(begin, end - begin)) +
         (end < text.size() ? "..." : "");
}

}  // namespace metro
