// calibrate registry history|drift|due|export: queries of the calibration registry
// (docs/registry.md). Its flags are bound in main.cpp, the program's one translation unit with
// CLI11.
#pragma once

#include <string>

#include "metro/registry/registry.hpp"

namespace metro::calibrate_app {

struct RegistryQueryOptions {
  std::string url;
  std::string device_id;
  bool json = false;
  double interval_days = kDefaultRecalibrationIntervalDays;
  std::string at_utc;  // `due`: the time to judge at (default now)
  bool all = false;    // `due`: every device, due or not
  std::string format = "csv";
  std::string output = "-";
};

int RunRegistryHistory(const RegistryQueryOptions& o);
int RunRegistryDrift(const RegistryQueryOptions& o);
int RunRegistryDue(const RegistryQueryOptions& o);
int RunRegistryExport(const RegistryQueryOptions& o);

}  // namespace metro::calibrate_app
