// The batch page: a row per session and tag with dead tags marked, the summary numbers as
// the JSON's rounded per GUM 7.2.6, a spread plot per quantity, links to the session pages.
#include "metro/report/batch_page.hpp"

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>
#include <string>

#include "core/json_text.hpp"
#include "metro/core/rounding.hpp"
#include "metro/report/html_report.hpp"
#include "report/html_dispatch.hpp"
#include "support/html_checks.hpp"

namespace metro {
namespace {

using nlohmann::ordered_json;

size_t Count(const std::string& text, const std::string& what) {
  size_t n = 0;
  for (size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

// Two sessions of two tags; tag 3 of the second session sent frames but no fresh packet.
ordered_json SummaryJson() {
  return ordered_json::parse(R"({
    "schema": "metro.batch-summary/1", "tool": {"name": "characterize", "version": "0.1.0"},
    "warnings": ["b.txt: sensor 3: no fresh packet"],
    "output_dir": "out", "sessions_total": 3, "sessions_failed": 1,
    "sessions": [
      {"input": "a.csv", "ok": true, "sha256": "aa", "report": "a.report.json",
       "page": "a.report.html",
       "tags": [{"sensor": 2, "name": "Chest", "frames": 0, "fresh": 0, "stale": 0, "never": 0,
                 "dead": false}],
       "quantities": [{"sensor": 2, "name": "Chest", "quantity": "ax_g", "unit": "g",
                       "mean": 0.01234, "u_mean": 0.0002, "n": 100.0}]},
      {"input": "b.txt", "ok": true, "sha256": "bb", "report": "b.report.json",
       "page": "b.report.html",
       "tags": [{"sensor": 2, "name": "Chest", "frames": 50, "fresh": 48, "stale": 2, "never": 0,
                 "dead": false},
                {"sensor": 3, "name": "Arm", "frames": 50, "fresh": 0, "stale": 0, "never": 50,
                 "dead": true}],
       "quantities": [{"sensor": 2, "name": "Chest", "quantity": "ax_g", "unit": "g",
                       "mean": 0.01266, "u_mean": 0.0003, "n": 48.0}]},
      {"input": "c.csv", "ok": false, "error": "c.csv:3:1: expected a number",
       "input_error": true}],
    "quantities": [{"sensor": 2, "name": "Chest", "quantity": "ax_g", "unit": "g", "sessions": 2,
                    "statistics": "linear", "mean_of_means": 0.0125,
                    "std_of_means": 0.000226274, "worst_n_eff_ratio": 0.5,
                    "worst_n_eff_session": "b.txt"}],
    "tags": []})");
}

// The same as the typed summary, read back as `characterize report` reads summary.json.
BatchSummaryReport Summary() {
  Result<BatchSummaryReport> summary =
      BatchSummaryFromJson(JsonText(SummaryJson(), 2), "out/summary.json");
  INFO((summary.ok() ? std::string() : summary.error().ToString()));
  REQUIRE(summary.ok());
  return summary.value();
}

TEST_CASE("Batch page has a row per session and tag with dead tags marked", "[report][batch]") {
  BatchPageOptions options;
  options.link_prefix = "out";
  Result<std::string> html = RenderBatchSummaryHtml(Summary(), options);
  REQUIRE(html.ok());
  const std::string& h = html.value();
  // Rows: a.csv x tag 2, b.txt x tags 2 and 3, c.csv failed.
  CHECK(Count(h, "<td><code>a.csv</code></td>") == 1);
  CHECK(Count(h, "<td><code>b.txt</code></td>") == 2);
  CHECK(Count(h, "DEAD: frames but no fresh packet") == 1);
  CHECK(h.find("dead tag rows (frames but no fresh packet): 1.") != std::string::npos);
  CHECK(h.find("FAILED: c.csv:3:1: expected a number") != std::string::npos);
  // Links relative to the page, to pages that batch wrote; none for the failed session.
  CHECK(h.find("href=\"out/a.report.html\"") != std::string::npos);
  CHECK(h.find("href=\"out/b.report.json\"") != std::string::npos);
  CHECK(Count(h, "href=\"out/") == 6);
  // Self-contained but for those links to the pages batch wrote beside it.
  CHECK(Count(h, "href=") == 6);
  for (const char* bad : {"http://", "https://", "src=", "@import", "<script", "<link", "<img"}) {
    INFO(bad);
    CHECK(h.find(bad) == std::string::npos);
  }
  CHECK(h.find("warning: b.txt: sensor 3: no fresh packet") != std::string::npos);
  // The summary numbers: mean 0.0125 g with the std of means 0.000226 g, per GUM 7.2.6.
  const RoundedResult r = RoundForStatement(0.0125, 0.000226274);
  CHECK(r.value == "0.01250");
  CHECK(r.uncertainty == "0.00023");
  CHECK(h.find("<td class=\"num\">" + r.value + "</td><td class=\"num\">" + r.uncertainty +
               "</td>") != std::string::npos);
  // One spread plot (one quantity).
  CHECK(Count(h, "<svg") == 1);
}

TEST_CASE("A saved batch summary renders as the batch page", "[report][batch]") {
  Result<std::string> html = RenderJsonHtml(SummaryJson(), "out/summary.json");
  REQUIRE(html.ok());
  CHECK(html.value().find("<title>Batch summary</title>") != std::string::npos);
  // Beside summary.json: links without a prefix.
  CHECK(html.value().find("href=\"a.report.html\"") != std::string::npos);
  // The same page as from the typed summary.
  Result<std::string> typed = RenderBatchSummaryHtml(Summary());
  REQUIRE(typed.ok());
  CHECK(testing::WithoutFooter(typed.value()) == testing::WithoutFooter(html.value()));
  // A summary without its sessions is refused at the object that lacks them (line 1, column
  // 1 of the text written with indent 2), naming the member.
  ordered_json bad = SummaryJson();
  bad.erase("sessions");
  Result<std::string> refused = RenderJsonHtml(bad, "out/summary.json");
  REQUIRE_FALSE(refused.ok());
  CHECK(refused.error().ToString() ==
        "out/summary.json:1:1: sessions: expected an array, found nothing (the member is "
        "missing)");
}

}  // namespace
}  // namespace metro
