// Test helpers: a TextSink that appends to a string, and a session loaded from CSV text (through
// a temporary file, as a user's file is).
#pragma once

#include <catch2/catch.hpp>
#include <string>
#include <string_view>

#include "metro/io/session_io.hpp"
#include "support/temp_file.hpp"

namespace metro::testing {

inline TextSink Into(std::string* text) {
  return [text](std::string_view chunk) {
    text->append(chunk);
    return Status::Ok();
  };
}

inline Session Load(const std::string& text) {
  TempFile file(text);
  auto s = LoadSession(file.path());
  if (!s.ok()) FAIL(s.error().ToString());
  return s.value();
}

}  // namespace metro::testing
