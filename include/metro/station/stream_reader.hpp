// The lines of a live raw stream (docs/station.md "Sources"): a serial port or pseudo-terminal
// (raw 8N1 through serial/serial_port.hpp), or a file another program is writing, followed as
// `tail -f` does. A port that disappears (unplugged, the other end closed) is reopened until it
// returns; the caller is told it was lost and when it came back, so that nothing is integrated
// across the gap.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "metro/core/status.hpp"

namespace metro::station {

struct StreamReaderOptions {
  int baud = 115200;           // Of a serial port (the Arduino sketches' usual rate).
  double idle_timeout_s = 10;  // No byte for this long: the stream has ended.
  double reconnect_s = 60;     // A lost port not back within this long: ended.

  bool IsValid(std::string* why) const;
};

class RawStreamReader {
 public:
  enum class Kind {
    kLine,     // `line` (without its newline), `line_number` (1-based, over the whole stream).
    kNothing,  // Nothing within the timeout.
    kLost,     // The port disappeared (`why`).
    kResumed,  // It came back (reopened); a partial first line is dropped.
    kEnded,    // The stream ended (`why`): idle, or the port did not come back.
  };
  struct Item {
    Kind kind = Kind::kNothing;
    std::string line;
    int64_t line_number = 0;
    std::string why;
  };

  // Opens `path`: a character device is a serial port (exclusive, raw, `baud`); a regular file
  // or FIFO is followed from its start. Errors name the path and the system's reason.
  static Result<std::unique_ptr<RawStreamReader>> Open(const std::string& path,
                                                       const StreamReaderOptions& options);
  ~RawStreamReader();
  RawStreamReader(const RawStreamReader&) = delete;
  RawStreamReader& operator=(const RawStreamReader&) = delete;

  // The next item, waiting at most timeout_ms for bytes.
  Item Next(int timeout_ms);
  bool IsPort() const;

 private:
  struct Impl;
  explicit RawStreamReader(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace metro::station
