// Every bundled budget produces what its description promises (issue #22): the test reads
// the "Expected: GUF ...; MCM ..." clause of each description and compares each number with
// the evaluation, to half a unit of its last written digit (and, for the Monte Carlo, to
// twice the run's own numerical tolerance, JCGM 101 7.9.2, if that is larger).
#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>
#include <string>

#include "metro/uncertainty/budget.hpp"
#include "metro/uncertainty/budget_report.hpp"

namespace metro {
namespace {

namespace fs = std::filesystem;

// Half a unit in the last digit of a number as written ("31.66" -> 0.005, "838" -> 0.5).
double HalfLastDigit(const std::string& written) {
  const size_t dot = written.find('.');
  const int decimals = dot == std::string::npos ? 0 : static_cast<int>(written.size() - dot - 1);
  return 0.5 * std::pow(10.0, -decimals);
}

void CheckNumber(const std::string& what, const std::string& written, double actual,
                 double at_least) {
  const double promised = std::stod(written);
  const double tolerance = std::max(HalfLastDigit(written), at_least);
  INFO(what << ": promised " << written << ", produced " << actual << " (tolerance " << tolerance
            << ")");
  CHECK(std::fabs(actual - promised) <= tolerance);
}

TEST_CASE("Every bundled budget produces what its description promises", "[uncertainty][budget]") {
  const std::regex scalar(R"((value|u|nu_eff|k|U) = (-?[0-9]+(?:\.[0-9]+)?))");
  const std::regex interval(
      R"((symmetric|shortest) ([0-9]+) % interval \[(-?[0-9.]+), (-?[0-9.]+)\])");
  int promising = 0;
  for (const auto& entry :
       fs::directory_iterator(std::string(METRO_SOURCE_DIR) + "/datasets/budgets")) {
    if (entry.path().extension() != ".json") continue;
    std::ifstream in(entry.path());
    const std::string description = nlohmann::json::parse(in).value("description", "");
    const size_t at = description.find("Expected: ");
    if (at == std::string::npos) continue;  // Promises no numbers.
    Result<Budget> budget = LoadBudget(entry.path().string());
    REQUIRE(budget.ok());
    ++promising;
    // The clause ends at the first ". " (a period ending a sentence, not a decimal point).
    size_t end = description.find(". ", at);
    if (end == std::string::npos) end = description.size();
    const std::string clause = description.substr(at + 10, end - at - 10);
    Result<BudgetEvaluation> e = EvaluateBudget(budget.value());
    REQUIRE(e.ok());
    const GumResult& g = e.value().gum;
    size_t from = 0;
    while (from < clause.size()) {
      size_t to = clause.find("; ", from);
      if (to == std::string::npos) to = clause.size();
      const std::string section = clause.substr(from, to - from);
      from = to + 2;
      const bool mcm = section.rfind("MCM ", 0) == 0;
      INFO(entry.path().filename().string() << ": " << section);
      REQUIRE((mcm || section.rfind("GUF ", 0) == 0));
      if (mcm) REQUIRE(e.value().monte_carlo);
      const double mc_floor = mcm ? 2.0 * e.value().monte_carlo->delta : 0.0;
      int numbers = 0;
      for (auto it = std::sregex_iterator(section.begin(), section.end(), scalar);
           it != std::sregex_iterator(); ++it, ++numbers) {
        const std::string key = (*it)[1];
        const std::string written = (*it)[2];
        if (mcm) {
          const McResult& m = *e.value().monte_carlo;
          REQUIRE((key == "value" || key == "u"));
          CheckNumber("MCM " + key, written, key == "value" ? m.value : m.u, mc_floor);
        } else {
          const double actual = key == "value"    ? g.value
                                : key == "u"      ? g.u
                                : key == "nu_eff" ? g.dof_eff
                                : key == "k"      ? g.k
                                                  : g.expanded;
          CheckNumber("GUF " + key, written, actual, 0.0);
        }
      }
      for (auto it = std::sregex_iterator(section.begin(), section.end(), interval);
           it != std::sregex_iterator(); ++it, ++numbers) {
        REQUIRE(mcm);
        const McResult& m = *e.value().monte_carlo;
        CHECK(std::stod((*it)[2]) / 100.0 == Approx(m.coverage));
        const CoverageInterval& iv = (*it)[1] == "shortest" ? m.shortest : m.symmetric;
        CheckNumber(std::string((*it)[1]) + " low", (*it)[3], iv.low, mc_floor);
        CheckNumber(std::string((*it)[1]) + " high", (*it)[4], iv.high, mc_floor);
      }
      CHECK(numbers >= 2);  // A section the patterns did not read is a broken promise.
    }
  }
  // GUM H.1, JCGM 101 9.2.2, 9.3 and 9.5 at least.
  CHECK(promising >= 4);
}

}  // namespace
}  // namespace metro
