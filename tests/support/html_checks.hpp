// Test helpers for the HTML reports: counting markers and checking that a page is
// self-contained (opens offline: nothing a browser would fetch).
#pragma once

#include <catch2/catch.hpp>
#include <cstddef>
#include <string>

namespace metro::testing {

// Occurrences of `what` in `text` (overlapping ones counted).
inline size_t Count(const std::string& text, const std::string& what) {
  size_t n = 0;
  for (size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

// A whole document with no URL, no src/href, no CSS import and url() only to fragments of
// the page itself (PLplot's clip paths: url(#...)).
inline void CheckSelfContained(const std::string& html) {
  CHECK(html.rfind("<!DOCTYPE html>", 0) == 0);
  CHECK(html.find("</html>") != std::string::npos);
  for (size_t at = html.find("url("); at != std::string::npos; at = html.find("url(", at + 1)) {
    CHECK(html.compare(at, 5, "url(#") == 0);
  }
  for (const char* bad :
       {"http://", "https://", "src=", "href=", "@import", "<script", "<link", "<iframe", "<img"}) {
    INFO(bad);
    CHECK(html.find(bad) == std::string::npos);
  }
}

// `html` without its footer, which carries the time the page was made: two renders of one
// document compare equal with it.
inline std::string WithoutFooter(const std::string& html) {
  const size_t begin = html.find("<footer>");
  const size_t end = html.find("</footer>", begin);
  if (begin == std::string::npos || end == std::string::npos) return html;
  return html.substr(0, begin) + html.substr(end + 9);
}

}  // namespace metro::testing
