// libFuzzer target: the push client's answer parsing (SLIP decoder, frame check, every
// response handler). The fuzzer's bytes are what the tag sends back; the client must fail
// cleanly, never crash, read out of bounds or loop without end.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "metro/blob/blob.hpp"
#include "metro/blob/push_client.hpp"

namespace {

class ScriptedTag : public metro::serial::ByteStream {
 public:
  ScriptedTag(const uint8_t* data, size_t size) : data_(data), size_(size) {}
  metro::Status Write(const uint8_t*, size_t) override { return metro::Status::Ok(); }
  metro::Result<size_t> Read(uint8_t* out, size_t capacity, int) override {
    if (pos_ >= size_) return metro::MakeError("hung up");  // ends every session
    // Answers arrive in pieces of 1..20 bytes, as over BLE.
    size_t n = 1 + data_[pos_] % 20;
    ++pos_;
    n = std::min({n, capacity, size_ - pos_});
    for (size_t i = 0; i < n; ++i) out[i] = data_[pos_ + i];
    pos_ += n;
    return n;
  }

 private:
  const uint8_t* data_;
  size_t size_;
  size_t pos_ = 0;
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  metro::blob::SlipDecoder decoder(38);
  for (size_t i = 0; i < size; ++i) (void)decoder.Feed(data[i]);

  ScriptedTag tag(data, size);
  metro::blob::PushOptions o;
  o.timeout_ms = 1;
  o.execute_timeout_ms = 1;
  o.max_retries = 1;
  metro::blob::PushClient client(&tag, o);
  (void)client.GetInfo();
  std::vector<uint8_t> blob(64, 0);
  blob[12] = 1;  // seq 1
  (void)client.Push(blob);
  return 0;
}
