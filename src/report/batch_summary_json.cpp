#include "batch_summary_json.hpp"

#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "core/json_text.hpp"

namespace metro {
namespace {

using Json = nlohmann::ordered_json;

// NaN (and an infinity) is written as null.
Json Number(double x) { return std::isfinite(x) ? Json(x) : Json(nullptr); }

// An array member that must be an array (an absent one fails as missing).
JsonCursor Array(const JsonCursor& c, std::string_view key) {
  const JsonCursor a = c[key];
  if (!a.IsArray()) a.Fail("an array");
  return a;
}

Json ToJsonValue(const BatchSessionTag& t) {
  return {{"sensor", t.sensor}, {"name", t.name},   {"frames", t.frames}, {"fresh", t.fresh},
          {"stale", t.stale},   {"never", t.never}, {"dead", t.dead}};
}

BatchSessionTag SessionTagFromJsonValue(const JsonCursor& c) {
  BatchSessionTag t;
  t.sensor = c["sensor"].Integer();
  t.name = c["name"].String();
  t.frames = c["frames"].Integer();
  t.fresh = c["fresh"].Integer();
  t.stale = c["stale"].Integer();
  t.never = c["never"].Integer();
  t.dead = c["dead"].Bool();
  return t;
}

Json ToJsonValue(const BatchSessionQuantity& q) {
  return {{"sensor", q.sensor}, {"name", q.name},         {"quantity", q.quantity},
          {"unit", q.unit},     {"mean", Number(q.mean)}, {"u_mean", Number(q.u_mean)},
          {"n", Number(q.n)}};
}

BatchSessionQuantity SessionQuantityFromJsonValue(const JsonCursor& c) {
  BatchSessionQuantity q;
  q.sensor = c["sensor"].Integer();
  q.name = c["name"].String();
  q.quantity = c["quantity"].String();
  q.unit = c["unit"].String();
  q.mean = c["mean"].NumberOrNaN();
  q.u_mean = c["u_mean"].NumberOrNaN();
  q.n = c["n"].NumberOrNaN();
  return q;
}

Json ToJsonValue(const BatchSessionEntry& s) {
  Json j;
  j["input"] = s.input;
  j["ok"] = s.ok;
  if (s.ok) {
    j["sha256"] = s.sha256;
    j["report"] = s.report;
    if (s.page) j["page"] = *s.page;
    if (s.tags) {
      Json tags = Json::array();
      for (const BatchSessionTag& t : *s.tags) tags.push_back(ToJsonValue(t));
      j["tags"] = std::move(tags);
    }
    if (s.quantities) {
      Json quantities = Json::array();
      for (const BatchSessionQuantity& q : *s.quantities) quantities.push_back(ToJsonValue(q));
      j["quantities"] = std::move(quantities);
    }
  } else {
    j["error"] = s.error;
    j["input_error"] = s.input_error;
  }
  return j;
}

BatchSessionEntry SessionFromJsonValue(const JsonCursor& c) {
  BatchSessionEntry s;
  s.input = c["input"].String();
  s.ok = c["ok"].Bool();
  if (s.ok) {
    s.sha256 = c["sha256"].String();
    s.report = c["report"].String();
    if (c.Has("page")) s.page = c["page"].String();
    if (c.Has("tags")) {
      const JsonCursor tags = Array(c, "tags");
      s.tags.emplace();
      for (size_t i = 0; i < tags.Size(); ++i) s.tags->push_back(SessionTagFromJsonValue(tags[i]));
    }
    if (c.Has("quantities")) {
      const JsonCursor quantities = Array(c, "quantities");
      s.quantities.emplace();
      for (size_t i = 0; i < quantities.Size(); ++i) {
        s.quantities->push_back(SessionQuantityFromJsonValue(quantities[i]));
      }
    }
  } else {
    s.error = c["error"].String();
    s.input_error = c["input_error"].Bool();
  }
  return s;
}

Json ToJsonValue(const BatchQuantitySummary& q) {
  Json j;
  j["sensor"] = q.sensor;
  j["name"] = q.name;
  j["quantity"] = q.quantity;
  j["unit"] = q.unit;
  j["sessions"] = q.sessions;
  if (q.statistics) j["statistics"] = *q.statistics;
  j["mean_of_means"] = Number(q.mean_of_means);
  j["std_of_means"] = Number(q.std_of_means);
  if (q.resultant_length) j["resultant_length"] = Number(*q.resultant_length);
  j["worst_n_eff_ratio"] = Number(q.worst_n_eff_ratio);
  j["worst_n_eff_session"] = q.worst_n_eff_session;
  if (q.warning) j["warning"] = *q.warning;
  return j;
}

BatchQuantitySummary QuantityFromJsonValue(const JsonCursor& c) {
  BatchQuantitySummary q;
  q.sensor = c["sensor"].Integer();
  q.name = c["name"].String();
  q.quantity = c["quantity"].String();
  q.unit = c["unit"].String();
  q.sessions = c["sessions"].Integer();
  if (c.Has("statistics")) {
    const JsonCursor statistics = c["statistics"];
    q.statistics = statistics.String();
    if (statistics.IsString() && *q.statistics != "circular" && *q.statistics != "linear") {
      statistics.Fail("\"circular\" or \"linear\"");
    }
  }
  q.mean_of_means = c["mean_of_means"].NumberOrNaN();
  q.std_of_means = c["std_of_means"].NumberOrNaN();
  if (c.Has("resultant_length")) q.resultant_length = c["resultant_length"].NumberOrNaN();
  q.worst_n_eff_ratio = c["worst_n_eff_ratio"].NumberOrNaN();
  q.worst_n_eff_session = c["worst_n_eff_session"].String();
  if (c.Has("warning")) q.warning = c["warning"].String();
  return q;
}

Json ToJsonValue(const BatchTagSummary& t) {
  Json j;
  j["sensor"] = t.sensor;
  j["name"] = t.name;
  j["sessions"] = t.sessions;
  j["frames"] = t.frames;
  j["fresh"] = t.fresh;
  j["stale"] = t.stale;
  j["never"] = t.never;
  j["packet_loss_ratio"] = Number(t.packet_loss_ratio);
  j["sessions_without_fresh"] = t.sessions_without_fresh;
  return j;
}

BatchTagSummary TagFromJsonValue(const JsonCursor& c) {
  BatchTagSummary t;
  t.sensor = c["sensor"].Integer();
  t.name = c["name"].String();
  t.sessions = c["sessions"].Integer();
  t.frames = c["frames"].Integer();
  t.fresh = c["fresh"].Integer();
  t.stale = c["stale"].Integer();
  t.never = c["never"].Integer();
  t.packet_loss_ratio = c["packet_loss_ratio"].NumberOrNaN();
  t.sessions_without_fresh = c["sessions_without_fresh"].Integer();
  return t;
}

}  // namespace

Json ToJsonValue(const BatchSummaryReport& summary) {
  Json j;
  j["schema"] = summary.schema;
  j["tool"] = {{"name", summary.tool.name}, {"version", summary.tool.version}};
  if (summary.warnings) j["warnings"] = *summary.warnings;
  j["output_dir"] = summary.output_dir;
  j["sessions_total"] = summary.sessions_total;
  j["sessions_failed"] = summary.sessions_failed;
  Json sessions = Json::array();
  for (const BatchSessionEntry& s : summary.sessions) sessions.push_back(ToJsonValue(s));
  j["sessions"] = std::move(sessions);
  Json quantities = Json::array();
  for (const BatchQuantitySummary& q : summary.quantities) quantities.push_back(ToJsonValue(q));
  j["quantities"] = std::move(quantities);
  if (summary.tags) {
    Json tags = Json::array();
    for (const BatchTagSummary& t : *summary.tags) tags.push_back(ToJsonValue(t));
    j["tags"] = std::move(tags);
  }
  return j;
}

BatchSummaryReport BatchSummaryFromJsonValue(const JsonCursor& c) {
  BatchSummaryReport r;
  if (!c.IsObject()) {
    c.Fail(std::string("a ") + kBatchSummarySchema + " object");
    return r;
  }
  const JsonCursor schema = c["schema"];
  r.schema = schema.String();
  if (schema.IsString() && r.schema != kBatchSummarySchema) {
    schema.Fail(std::string("\"") + kBatchSummarySchema + "\"");
    return r;
  }
  const JsonCursor tool = c["tool"];
  r.tool.name = tool["name"].String();
  r.tool.version = tool["version"].String();
  if (c.Has("warnings")) r.warnings = c["warnings"].Strings();
  r.output_dir = c["output_dir"].String();
  const JsonCursor total = c["sessions_total"];
  const JsonCursor failed = c["sessions_failed"];
  r.sessions_total = total.Integer();
  r.sessions_failed = failed.Integer();
  const JsonCursor sessions = Array(c, "sessions");
  for (size_t i = 0; i < sessions.Size(); ++i) {
    r.sessions.push_back(SessionFromJsonValue(sessions[i]));
  }
  const JsonCursor quantities = Array(c, "quantities");
  for (size_t i = 0; i < quantities.Size(); ++i) {
    r.quantities.push_back(QuantityFromJsonValue(quantities[i]));
  }
  if (c.Has("tags")) {
    const JsonCursor tags = Array(c, "tags");
    r.tags.emplace();
    for (size_t i = 0; i < tags.Size(); ++i) r.tags->push_back(TagFromJsonValue(tags[i]));
  }
  // The counts batch wrote from the sessions themselves: a summary that disagrees was edited.
  if (c.ok()) {
    int64_t failed_sessions = 0;
    for (const BatchSessionEntry& s : r.sessions) failed_sessions += s.ok ? 0 : 1;
    if (r.sessions_total != static_cast<int64_t>(r.sessions.size())) {
      total.Fail("the number of \"sessions\" (" + std::to_string(r.sessions.size()) + ")");
    } else if (r.sessions_failed != failed_sessions) {
      failed.Fail("the number of \"sessions\" with \"ok\": false (" +
                  std::to_string(failed_sessions) + ")");
    }
  }
  return r;
}

std::string ToJson(const BatchSummaryReport& summary) { return JsonText(ToJsonValue(summary), 2); }

Result<BatchSummaryReport> BatchSummaryFromJson(std::string_view text, const std::string& file) {
  return ReadJsonText<BatchSummaryReport>(text, file, BatchSummaryFromJsonValue);
}

}  // namespace metro
