#include "schema.hpp"

#include <fmt/format.h>

#include <chrono>
#include <thread>

#include "metro/registry/registry.hpp"

namespace metro::registry_internal {

std::vector<std::string> MigrationTo(int version, const SqlBackend& db) {
  const std::string id = db.AutoIdColumn();
  const std::string cal_ref = "BIGINT NOT NULL REFERENCES calibrations(id)";
  switch (version) {
    case 1:
      return {
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

Result<int> ReadSchemaVersion(SqlBackend* db) {
  if (Status s = db->Execute("CREATE TABLE IF NOT EXISTS schema_version (version INTEGER NOT NULL)",
                             {}, nullptr);
      !s.ok()) {
    return s.error();
  }
  std::vector<SqlRow> rows;
  if (Status s = db->Execute("SELECT version FROM schema_version", {}, &rows); !s.ok()) {
    return s.error();
  }
  if (rows.empty() || !rows[0][0]) return 0;
  return std::stoi(*rows[0][0]);
}

Result<int> Migrate(SqlBackend* db, int target, const std::string& url) {
  for (int attempt = 0;; ++attempt) {
    int version = 0;
    Status s = db->Begin(/*exclusive=*/true);
    if (s.ok()) {
      Result<int> v = ReadSchemaVersion(db);
      if (!v.ok()) {
        s = v.status();
      } else {
        version = v.value();
        if (version > kRegistrySchemaVersion) {
          db->Rollback();
          return MakeError(url, 0,
                           fmt::format("the registry's schema is version {}, newer than this "
                                       "program's {}; use a newer metro",
                                       version, kRegistrySchemaVersion));
        }
        if (version >= target) {
          db->Rollback();
          return version;
        }
        for (const std::string& sql : MigrationTo(version + 1, *db)) {
          s = db->Execute(sql, {}, nullptr);
          if (!s.ok()) break;
        }
        if (s.ok()) s = db->Commit();
      }
    }
    if (s.ok()) continue;  // The next version, in its own transaction.
    const bool retry = db->LastErrorRetryable();
    db->Rollback();
    if (!retry || attempt > 200) return s.error();
    std::this_thread::sleep_for(std::chrono::milliseconds(5 + 5 * (attempt % 10)));
  }
}

}  // namespace metro::registry_internal
