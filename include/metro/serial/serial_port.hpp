// A serial port (or pseudo-terminal) as a ByteStream: termios raw 8N1 at the receiver's
// 230400 baud (the push protocol and the capture), no flow control, reads with poll() timeouts.
// POSIX only.
#pragma once

#include <memory>
#include <string>

#include "metro/core/status.hpp"
#include "metro/serial/byte_stream.hpp"

namespace metro::serial {

// The nRF52840 receiver's serial link (thesis ch. 8): capture and push.
inline constexpr int kReceiverBaud = 230400;

class SerialPort : public ByteStream {
 public:
  // Opens `path` (O_NOCTTY), takes an exclusive flock (another program on the same port is an
  // error), sets raw 8N1 at `baud` (9600, 19200, 38400, 57600, 115200, 230400, 460800 or
  // 921600) and flushes stale input. Errors name the path and the system's reason.
  static Result<std::unique_ptr<SerialPort>> Open(const std::string& path,
                                                  int baud = kReceiverBaud);
  ~SerialPort() override;
  SerialPort(const SerialPort&) = delete;
  SerialPort& operator=(const SerialPort&) = delete;

  Status Write(const uint8_t* data, size_t size) override;
  // 0 bytes after timeout_ms; error "hung up" when the other end closed (POLLHUP, EIO).
  Result<size_t> Read(uint8_t* data, size_t capacity, int timeout_ms) override;

 private:
  SerialPort(int fd, std::string path) : fd_(fd), path_(std::move(path)) {}
  int fd_;
  std::string path_;
};

}  // namespace metro::serial
