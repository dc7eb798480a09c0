#include "metro/core/utc_time.hpp"

namespace metro {

std::string UtcIso8601(std::time_t t) {
  std::tm tm{};
  if (::gmtime_r(&t, &tm) == nullptr) return {};
  char buf[32];
  if (std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm) == 0) return {};
  return buf;
}

std::string UtcIso8601Now() { return UtcIso8601(std::time(nullptr)); }

}  // namespace metro
