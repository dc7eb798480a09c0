// characterize simulate -o FILE [--kind static|table|calibration|thermal] ...: sessions with
// known truth (docs/simulator.md).
#pragma once

#include <string>

#include "metro/sim/calibration_session.hpp"
#include "metro/sim/static_session.hpp"
#include "metro/sim/table_session.hpp"
#include "metro/sim/thermal_session.hpp"

namespace metro::apps {

struct SimulateOptions {
  std::string output;
  std::string format = "csv";
  std::string columns = "angles";
  int tags = 0;
  StaticSimulationOptions sim;
  // --kind table: a rotation-table session (docs/simulator.md, "Rotation-table sessions").
  std::string kind = "static";
  std::string table_axis = "yaw";
  std::string reference_output;
  std::string truth_output;  // Default: <output>.truth.json when -o names a file.
  std::string table_readout = "continuous";
  TableSimulationOptions table;
  // --kind calibration: a multi-pose calibration session (docs/simulator.md, "Calibration
  // sessions"); --seed, --sensor and --rate-hz are shared.
  SimulationOptions calibration = DefaultCalibrationSimulation();
  bool no_temperature = false;
  // --kind thermal: one pose over a temperature profile (docs/simulator.md, "Thermal sessions").
  ThermalSimulationOptions thermal;
  std::string thermal_profile = "ramp";

  static SimulationOptions DefaultCalibrationSimulation() {
    SimulationOptions c;
    c.table_rates_dps = {90.0};
    c.temperature = true;
    c.temp_start_c = 22.0;
    c.temp_end_c = 34.0;
    return c;
  }
};

int RunSimulate(SimulateOptions o);

}  // namespace metro::apps
