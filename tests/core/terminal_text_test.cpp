#include "metro/core/terminal_text.hpp"

#include <catch2/catch.hpp>
#include <string>

namespace metro {
namespace {

TEST_CASE("EscapeControlChars: C0, DEL, C1 and non-UTF-8 bytes are escaped", "[core][security]") {
  CHECK(EscapeControlChars("plain name.csv") == "plain name.csv");
  CHECK(EscapeControlChars("a\nb\rc\td") == "a\\nb\\rc\\td");
  // ESC sequences: a clear screen (CSI 2J) and a window title (OSC 0 ... BEL).
  CHECK(EscapeControlChars("x\x1b[2J\x1b]0;t\x07y") == "x\\x1b[2J\\x1b]0;t\\x07y");
  CHECK(EscapeControlChars(std::string("\0\x7f", 2)) == "\\x00\\x7f");
  // U+009B (CSI as a C1 control, UTF-8 C2 9B) and U+0085 (NEL, a line break).
  CHECK(EscapeControlChars("a\xc2\x9b"
                           "31mb\xc2\x85") == "a\\u009b31mb\\u0085");
  // Valid UTF-8 passes: U+00E9, U+20AC, U+1F600.
  CHECK(EscapeControlChars("caf\xc3\xa9 \xe2\x82\xac \xf0\x9f\x98\x80") ==
        "caf\xc3\xa9 \xe2\x82\xac \xf0\x9f\x98\x80");
  // Bytes that are not UTF-8: a lone 0x9B (8-bit CSI), a truncated sequence, overlong forms,
  // a surrogate.
  CHECK(EscapeControlChars("\x9b"
                           "2J") == "\\x9b2J");
  CHECK(EscapeControlChars("\xe2\x82") == "\\xe2\\x82");
  CHECK(EscapeControlChars("\xc0\x8a") == "\\xc0\\x8a");
  CHECK(EscapeControlChars("\xe0\x80\x8a") == "\\xe0\\x80\\x8a");
  CHECK(EscapeControlChars("\xed\xa0\x80") == "\\xed\\xa0\\x80");
  CHECK(EscapeControlChars("\xf4\x90\x80\x80") == "\\xf4\\x90\\x80\\x80");
}

TEST_CASE("EscapeControlChars is idempotent; the KeepLines form keeps newlines and tabs",
          "[core][security]") {
  const std::string hostile = "t\x1b[31m\n\tq\xc2\x9b\xff";
  const std::string once = EscapeControlChars(hostile);
  CHECK(EscapeControlChars(once) == once);
  CHECK(EscapeControlCharsKeepLines("row 1\tx\nrow\x1b[2K 2\n") == "row 1\tx\nrow\\x1b[2K 2\n");
  CHECK(EscapeControlCharsKeepLines("a\rb") == "a\\rb");
}

TEST_CASE("Excerpt quotes a long text by a window around a byte, cut with ellipses",
          "[core][security][issue37]") {
  CHECK(Excerpt("x + y", 2) == "x + y");  // Short: whole.
  CHECK(Excerpt("a\nb", 0) == "a\\nb");   // Escaped like EscapeControlChars.
  // 1000 'a', then "ERR", then 1000 'b': 12 bytes around "ERR", a third of them before it.
  const std::string text = std::string(1000, 'a') + "ERR" + std::string(1000, 'b');
  CHECK(Excerpt(text, 1000, 12) == "...aaaaERRbbbbb...");
  // From the start, and a window that ends at the text's end keeps its width.
  CHECK(Excerpt(text, std::string::npos, 6) == "aaaaaa...");
  CHECK(Excerpt(text, text.size() - 1, 6) == "...bbbbbb");
  // The default width: 120 bytes of the text plus the two ellipses.
  CHECK(Excerpt(text, 1000).size() == 126);
  // A UTF-8 sequence is never cut: U+00E9 (2 bytes) at the window's edges.
  const std::string accents =
      std::string(10, 'a') + "\xc3\xa9\xc3\xa9\xc3\xa9" + std::string(10, 'b');
  const std::string cut = Excerpt(accents, 10, 5);
  CHECK(cut.find("\\x") == std::string::npos);  // No escaped half sequence.
}

}  // namespace
}  // namespace metro
