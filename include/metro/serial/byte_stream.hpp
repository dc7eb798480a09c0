// A bidirectional byte link: what the push client (blob) and the receiver capture (capture)
// talk through, a serial port (serial_port.hpp), a pseudo-terminal or a test's scripted peer.
#pragma once

#include <cstddef>
#include <cstdint>

#include "metro/core/status.hpp"

namespace metro::serial {

// A bidirectional byte link.
class ByteStream {
 public:
  virtual ~ByteStream() = default;
  // Writes every byte (blocking). Error when the link is gone.
  virtual Status Write(const uint8_t* data, size_t size) = 0;
  // Reads at most `capacity` bytes, waiting up to timeout_ms for the first one; 0 bytes means
  // the timeout passed. Error when the link hung up or failed.
  virtual Result<size_t> Read(uint8_t* data, size_t capacity, int timeout_ms) = 0;
};

}  // namespace metro::serial
