// characterize capture --port DEV -o capture.txt: the receiver's live capture (docs/capture.md).
#pragma once

#include <string>

#include "metro/capture/capture.hpp"

namespace metro::apps {

struct CaptureCliOptions {
  std::string port;
  int baud = 230400;
  double duration_s = 0.0;
  std::string output;
  std::string capture;
  bool force = false;
  bool reconnect = false;
  bool no_reconnect = false;
  double frame_period_s = kReceiverFramePeriodS;
  bool analyze = false;
  std::string tags;  // --tags FILE: the tags' names under the live view and the final table.
};

int RunCaptureCommand(const CaptureCliOptions& c);

}  // namespace metro::apps
