// characterize budget / --budget: units are quantities (issue #21 part 5). A model that mixes
// units and a session quantity in an incompatible unit exit 2 naming the file and the input;
// a session's pitch in degrees used as an input in rad is converted and the conversion shown.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <nlohmann/json.hpp>
#include <string>

#include "support/run_program.hpp"
#include "support/temp_file.hpp"

namespace metro {
namespace {

using testing::TempFile;

const std::string kDatasets = std::string(METRO_SOURCE_DIR) + "/datasets/";

testing::ProgramRun Characterize(const std::string& args) {
  return testing::RunProgram(METRO_CHARACTERIZE_EXE, args);
}

TEST_CASE("characterize budget refuses a model adding rad to deg with exit 2", "[apps][units]") {
  TempFile budget(R"({"measurand": {"name": "y", "unit": "rad", "model": "a + b"},
    "inputs": [{"name": "a", "value": 0.5, "u": 0.01, "unit": "rad"},
               {"name": "b", "value": 30, "u": 0.1, "unit": "deg"}], "monte_carlo": false})",
                  ".json");
  const auto r = Characterize("budget " + budget.path());
  CHECK(r.exit_code == 2);
  CHECK(r.out.empty());
  // The '+' (column 3 of the model) at file:line:column.
  CHECK(r.err.find(budget.path() + ":1:56: model 'a + b', column 3: a sum: 'a' (rad) and 'b' "
                                   "(deg) are in different units") != std::string::npos);
}

TEST_CASE("characterize budget quotes a 1 MB model once, cut, at file:line:column",
          "[apps][security][issue37]") {
  // issue #37: the error echoed the whole model twice, 2 MB on one line.
  std::string model = "x";
  while (model.size() < 1000000) model += " + x";
  TempFile budget("{\"measurand\": {\"name\": \"y\",\n \"model\": \"" + model +
                      "\"}, \"inputs\": [{\"name\": \"x\", \"value\": 1, \"u\": 0.1}]}",
                  ".json");
  const auto r = Characterize("budget " + budget.path());
  CHECK(r.exit_code == 2);
  CHECK(r.out.empty());
  INFO(r.err.substr(0, 500));
  CHECK(r.err.size() < 500);
  CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
  // Byte 19999 of the model (past muparser's limit), the model starting at line 2 column 12.
  CHECK(r.err.rfind("error: " + budget.path() + ":2:20011: model '...", 0) == 0);
  CHECK(r.err.find("1000001 bytes; muparser reads a model of at most 19999 bytes") !=
        std::string::npos);
}

TEST_CASE("characterize budget refuses a measurand unit the model does not give", "[apps][units]") {
  TempFile budget(R"({"measurand": {"name": "m", "unit": "mg", "model": "x"},
    "inputs": [{"name": "x", "value": 0.1, "u": 1e-6, "unit": "kg"}], "monte_carlo": false})",
                  ".json");
  const auto r = Characterize("budget " + budget.path());
  CHECK(r.exit_code == 2);
  CHECK(r.err.find("measurand 'm' is declared in 'mg' but the model 'x' gives kg") !=
        std::string::npos);
}

TEST_CASE("characterize --budget converts the session's pitch in deg to an input in rad",
          "[apps][units]") {
  TempFile budget(R"({"measurand": {"name": "pitch", "unit": "rad", "model": "obs"},
    "inputs": [{"name": "obs", "type_a": {"sensor": 2, "quantity": "pitch_deg"}, "unit": "rad"}],
    "monte_carlo": false})",
                  ".json");
  const auto r = Characterize(kDatasets + "static_chest.csv --type-a --quantity pitch_deg " +
                              "--budget " + budget.path());
  REQUIRE(r.exit_code == 0);
  const auto report = nlohmann::json::parse(r.out);
  const nlohmann::json* pitch = nullptr;
  for (const auto& sensor : report["sensors"]) {
    if (sensor["sensor"] == 2) pitch = &sensor["quantities"]["pitch_deg"]["type_a"];
  }
  REQUIRE(pitch != nullptr);
  const auto& line = report["budget"]["budget"][0];
  const double deg_to_rad = 3.14159265358979323846 / 180.0;
  CHECK(line["unit"] == "rad");
  CHECK(line["value"].get<double>() ==
        Approx((*pitch)["mean"].get<double>() * deg_to_rad).epsilon(1e-14));
  CHECK(line["unit_conversion"]["from"] == "deg");
  CHECK(line["unit_conversion"]["to"] == "rad");
  CHECK(line["unit_conversion"]["value_from"].get<double>() == (*pitch)["mean"].get<double>());
  CHECK(report["budget"]["result"]["value"].get<double>() == line["value"].get<double>());
}

TEST_CASE("characterize --budget refuses a session quantity in an incompatible unit",
          "[apps][units]") {
  TempFile budget(R"({"measurand": {"name": "t", "unit": "s", "model": "obs"},
    "inputs": [{"name": "obs", "type_a": {"sensor": 2, "quantity": "pitch_deg"}, "unit": "s"}],
    "monte_carlo": false})",
                  ".json");
  const auto r = Characterize(kDatasets + "static_chest.csv --type-a --quantity pitch_deg " +
                              "--budget " + budget.path());
  CHECK(r.exit_code == 2);
  CHECK(r.err.find("input 'obs': session quantity 'pitch_deg' is in deg, which cannot be "
                   "converted to the input's unit 's'") != std::string::npos);
}

TEST_CASE("characterize budget names an input without a variance before sampling", "[apps][mc]") {
  // issue #22: three readings give t_2, which has no variance (JCGM 101 6.4.9.4).
  TempFile budget(R"({"measurand": {"name": "y", "model": "x + z"},
    "inputs": [{"name": "x", "type_a": {"values": [1.0, 1.1, 0.95]}},
               {"name": "z", "value": 0, "u": 0.01}],
    "monte_carlo": {"trials": 100000, "seed": 1}})",
                  ".json");
  const auto r = Characterize("budget " + budget.path());
  REQUIRE(r.exit_code == 0);
  CHECK(r.err.find("warning: input x (nu = 2) has no variance in the Monte Carlo method") == 0);
  const auto j = nlohmann::json::parse(r.out);
  CHECK(j["result"]["derivatives"] == "exact (symbolic, GiNaC)");
  const auto& mc = j["monte_carlo"];
  CHECK(mc["u"].is_null());
  CHECK(mc["u_defined"] == false);
  CHECK(mc["mean_defined"] == true);
  CHECK(mc["inputs_without_variance"] == nlohmann::json::array({"x (nu = 2)"}));
  CHECK(mc["interval_symmetric"][0].get<double>() < mc["interval_symmetric"][1].get<double>());
}

}  // namespace
}  // namespace metro
