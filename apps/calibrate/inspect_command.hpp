// calibrate inspect tag.bin|tag.hex: a blob decoded and checked as the firmware would.
// Its flags are bound in main.cpp, the program's one translation unit with CLI11.
#pragma once

#include <string>

namespace metro::calibrate_app {

struct InspectCliOptions {
  std::string input;
  std::string device_id;
  std::string slot_address = "0x3B000";
  bool json = false;
  std::string tags;  // --tags FILE: name the tag of each blob's device
  int sensor = 0;    // with --tags: check against this tag's device
};

int RunInspect(const InspectCliOptions& o);

}  // namespace metro::calibrate_app
