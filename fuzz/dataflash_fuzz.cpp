// libFuzzer target: ArduPilot DataFlash logs (metro/io/dataflash.hpp), read strictly and
// with --lenient (FMT-described messages, the topics listing), then loaded as a session (the
// IMU, IMU2, IMU3 tags, --time-order sort and refuse).
#include <cstddef>
#include <cstdint>

#include "fuzz_input.hpp"
#include "metro/io/dataflash.hpp"
#include "metro/io/session_io.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string& path = metro_fuzz::WriteInput(data, size, "log.bin");
  for (bool lenient : {false, true}) {
    metro::DataFlashReadOptions read;
    read.lenient = lenient;
    auto log = metro::ReadDataFlash(path, read);
    if (log.ok()) (void)metro::FormatDataFlashTopics(log.value());
    metro::LoadOptions options;
    options.format = metro::SessionFormat::kDataFlash;
    options.lenient = lenient;
    (void)metro::LoadSession(path, options);
    options.time_order = metro::LoadOptions::TimeOrder::kRefuse;
    (void)metro::LoadSession(path, options);
  }
  return 0;
}
