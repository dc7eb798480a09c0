#include "schema.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cstdint>
#include <thread>

#include "metro/registry/registry.hpp"

namespace metro::registry_internal {

std::vector<std::string> MigrationTo(int version, const SqlBackend& db) {
  const std::string id = db.AutoIdColumn();
  const std::string cal_ref = "BIGINT NOT NULL REFERENCES calibrations(id)";
  switch (version) {
    case 1:
      return {
          "CREATE TABLE schema_version (version INTEGER NOT NULL)",
          "CREATE TABLE calibrations (id " + id +
              ", certificate_id TEXT NOT NULL, sensor INTEGER NOT NULL, date_utc TEXT NOT NULL, "
              "recorded_utc TEXT NOT NULL, tool_version TEXT NOT NULL, covariance_json TEXT NOT "
              "NULL, UNIQUE (certificate_id, sensor))",
          "CREATE TABLE calibration_inputs (calibration_id " + cal_ref +
              ", position INTEGER NOT NULL, path TEXT NOT NULL, sha256 TEXT NOT NULL, PRIMARY "
              "KEY (calibration_id, position))",
          "CREATE TABLE constants (calibration_id " + cal_ref +
              ", position INTEGER NOT NULL, name TEXT NOT NULL, value DOUBLE PRECISION NOT NULL, "
              "u DOUBLE PRECISION NOT NULL, unit TEXT NOT NULL, PRIMARY KEY (calibration_id, "
              "name))",
          "CREATE TABLE device_calibrations (device_id TEXT NOT NULL, calibration_id " + cal_ref +
              ", source TEXT NOT NULL, recorded_utc TEXT NOT NULL, PRIMARY KEY (device_id, "
              "calibration_id))",
          "CREATE TABLE blobs (id " + id + ", device_id TEXT NOT NULL, calibration_id " + cal_ref +
              ", seq BIGINT NOT NULL, crc BIGINT NOT NULL, accel_t_valid_min_c DOUBLE PRECISION, "
              "accel_t_valid_max_c DOUBLE PRECISION, gyro_t_valid_min_c DOUBLE PRECISION, "
              "gyro_t_valid_max_c DOUBLE PRECISION, file TEXT NOT NULL, recorded_utc TEXT NOT "
              "NULL)",
          "CREATE TABLE pushes (id " + id + ", device_id TEXT NOT NULL, calibration_id " + cal_ref +
              ", port TEXT NOT NULL, ok INTEGER NOT NULL, result TEXT NOT NULL, readback TEXT NOT "
              "NULL, recorded_utc TEXT NOT NULL)",
          "INSERT INTO schema_version (version) VALUES (1)",
      };
    case 2:
      // Station and operator of each calibration; conformity decisions (issue #27 point 3).
      return {
          "ALTER TABLE calibrations ADD COLUMN station TEXT NOT NULL DEFAULT ''",
          "ALTER TABLE calibrations ADD COLUMN operator_name TEXT NOT NULL DEFAULT ''",
          "CREATE TABLE conformity (calibration_id " + cal_ref +
              ", position INTEGER NOT NULL, constant TEXT NOT NULL, value DOUBLE PRECISION NOT "
              "NULL, u DOUBLE PRECISION NOT NULL, lower_limit DOUBLE PRECISION, upper_limit "
              "DOUBLE PRECISION, unit TEXT NOT NULL, acceptance_lower DOUBLE PRECISION, "
              "acceptance_upper DOUBLE PRECISION, p_conformance DOUBLE PRECISION NOT NULL, "
              "decision TEXT NOT NULL, decision_rule TEXT NOT NULL, coverage_factor DOUBLE "
              "PRECISION NOT NULL, max_consumer_risk DOUBLE PRECISION NOT NULL, PRIMARY KEY "
              "(calibration_id, constant))",
          "CREATE INDEX device_calibrations_by_calibration ON device_calibrations "
          "(calibration_id)",
          "UPDATE schema_version SET version = 2",
      };
    default:
      return {};
  }
}

std::vector<std::string> TablesOf(int version) {
  std::vector<std::string> tables;
  if (version >= 1) {
    tables = {"blobs",  "calibration_inputs", "calibrations", "constants", "device_calibrations",
              "pushes", "schema_version"};
  }
  if (version >= 2) tables.push_back("conformity");
  std::sort(tables.begin(), tables.end());
  return tables;
}

namespace {

std::string Expected() {
  return fmt::format(
      "expected one row holding a whole number from 1 to {} (this program's "
      "version)",
      kRegistrySchemaVersion);
}

std::string Quoted(const std::string& text) {
  return "'" + (text.size() > 40 ? text.substr(0, 40) + "..." : text) + "'";
}

}  // namespace

Result<int> ReadSchemaVersion(SqlBackend* db, const std::string& url) {
  std::vector<SqlRow> rows;
  if (Status s = db->Execute(db->TablesSql(), {}, &rows); !s.ok()) return s.error();
  std::vector<std::string> tables;
  for (const SqlRow& r : rows) tables.push_back(r.empty() || !r[0] ? std::string() : *r[0]);
  std::sort(tables.begin(), tables.end());
  if (tables.empty()) return 0;
  if (!std::binary_search(tables.begin(), tables.end(), std::string("schema_version"))) {
    std::string names;
    for (size_t i = 0; i < tables.size() && i < 5; ++i) names += (i ? ", " : "") + tables[i];
    if (tables.size() > 5) names += fmt::format(", ... ({} tables)", tables.size());
    return MakeError(url, 0,
                     fmt::format("not a metro registry: it has tables ({}) but no schema_version; "
                                 "metro changes nothing in it: name a new file for the registry",
                                 names));
  }
  rows.clear();
  if (Status s = db->Execute("SELECT version FROM schema_version", {}, &rows); !s.ok()) {
    return MakeError(url, 0, "not a metro registry: " + s.error().message);
  }
  if (rows.size() != 1) {
    return MakeError(url, 0,
                     fmt::format("schema_version has {} rows; {}", rows.size(), Expected()));
  }
  if (rows[0].empty() || !rows[0][0]) {
    return MakeError(url, 0, "schema_version holds NULL; " + Expected());
  }
  const std::string& text = *rows[0][0];
  int64_t version = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), version);
  if (ec != std::errc() || end != text.data() + text.size() || text.empty()) {
    return MakeError(
        url, 0,
        fmt::format("schema_version holds {}, not a whole number; {}", Quoted(text), Expected()));
  }
  if (version > kRegistrySchemaVersion) {
    return MakeError(url, 0,
                     fmt::format("the registry's schema is version {}, newer than this "
                                 "program's {}; use a newer metro",
                                 version, kRegistrySchemaVersion));
  }
  if (version < 1) {
    return MakeError(url, 0,
                     fmt::format("schema_version holds {}, not a version metro writes; {}", version,
                                 Expected()));
  }
  const int v = static_cast<int>(version);
  for (const std::string& table : TablesOf(v)) {
    if (!std::binary_search(tables.begin(), tables.end(), table)) {
      return MakeError(
          url, 0,
          fmt::format("not a metro registry of version {}: the table {} is missing", v, table));
    }
  }
  return v;
}

Result<int> Migrate(SqlBackend* db, int target, const std::string& url) {
  for (int attempt = 0;; ++attempt) {
    Status s = db->Begin(/*exclusive=*/true);
    if (s.ok()) {
      Result<int> v = ReadSchemaVersion(db, url);
      if (!v.ok() && !db->LastErrorRetryable()) {
        db->Rollback();
        return v.error();
      }
      if (v.ok() && v.value() >= target) {
        db->Rollback();  // Nothing to change.
        return v.value();
      }
      s = v.status();
      // Every step from the version found to this program's, in this one transaction.
      for (int next = v.ok() ? v.value() + 1 : target + 1; s.ok() && next <= target; ++next) {
        for (const std::string& sql : MigrationTo(next, *db)) {
          s = db->Execute(sql, {}, nullptr);
          if (!s.ok()) break;
        }
      }
      if (s.ok()) s = db->Commit();
      if (s.ok()) return target;
    }
    const bool retry = db->LastErrorRetryable();
    db->Rollback();
    if (!retry || attempt >= 200) return s.error();
    std::this_thread::sleep_for(std::chrono::milliseconds(5 + 5 * (attempt % 10)));
  }
}

}  // namespace metro::registry_internal
