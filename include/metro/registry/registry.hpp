// The calibration registry: every calibration, blob and push of a line's tags, in a SQLite file
// or a PostgreSQL database (docs/registry.md), and the queries over it: a device's history, the
// drift of its constants between its last two calibrations, the devices due for recalibration,
// and an export.
//
// URL: a plain path is a SQLite file (created when absent); "postgresql://..." or
// "postgres://..." is a libpq connection URI. One schema for both, versioned in
// `schema_version` and migrated forward on open (all steps in one transaction); a database
// whose version is newer than kRegistrySchemaVersion, or that is not a metro registry, is
// refused. Every value read back is checked (a bad one is an input error naming the table,
// the column and the value). Every record is one
// transaction: a failure leaves nothing of it behind. Concurrent writers (several processes,
// several stations) are safe: SQLite in WAL mode with a busy timeout and BEGIN IMMEDIATE,
// retried on SQLITE_BUSY; PostgreSQL retried on serialization failures.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "metro/calibration/calibrate.hpp"
#include "metro/calibration/conformity.hpp"
#include "metro/core/status.hpp"

namespace metro {

inline constexpr int kRegistrySchemaVersion = 2;
// `calibrate registry due`: the recalibration interval unless --interval-days says otherwise
// (docs/registry.md: a year, the common starting interval of ILAC G24:2007 / OIML D 10 for
// an instrument without a drift history).
inline constexpr double kDefaultRecalibrationIntervalDays = 365.0;

// Who and where, for each record. recorded_utc empty: now.
struct RecordContext {
  std::string station;
  std::string operator_name;
  std::string recorded_utc;
};

struct RegistryConstant {
  std::string name;  // "accel.b_x" (named_constants.hpp)
  double value = 0.0;
  double u = 0.0;
  std::string unit;
};

struct RegistryBlob {
  uint64_t device_id = 0;
  uint32_t seq = 0;
  uint32_t crc = 0;  // CRC-32 of the blob as written (calibration-blob.md).
  std::optional<double> accel_t_valid_min_c, accel_t_valid_max_c;
  std::optional<double> gyro_t_valid_min_c, gyro_t_valid_max_c;
  std::string file;  // Where it was written ("-" for stdout).
  std::string recorded_utc;
};

struct RegistryPush {
  uint64_t device_id = 0;
  std::string port;
  bool ok = false;
  std::string result;    // The push's one-line result.
  std::string readback;  // "verified" / what the read-back found.
  std::string recorded_utc;
};

struct RegistryCalibration {
  int64_t id = 0;
  std::string certificate_id;  // CalibrationCertificateId of the calibration.json.
  int sensor = 0;              // The tag in calibration.json.
  std::string date_utc;        // Of the fit.
  std::string recorded_utc;
  std::string tool_version;
  std::string station;
  std::string operator_name;
  std::vector<InputFile> inputs;
  std::vector<RegistryConstant> constants;
  std::string covariance_json;  // {"accel": {"parameters": [...], "covariance": [[...]]}, ...}
  std::optional<ConformityStatement> conformity;
  std::vector<RegistryBlob> blobs;   // With `History` only.
  std::vector<RegistryPush> pushes;  // With `History` only.
  std::vector<uint64_t> devices;     // Devices it belongs to.
};

struct DriftConstant {
  std::string name;
  std::string unit;
  double from = 0.0;
  double to = 0.0;
  double change = 0.0;    // to - from
  double u_change = 0.0;  // sqrt(u1^2 + u2^2 - 2 cov), cov = 0 (docs/registry.md)
  double en = 0.0;        // change / u_change (ISO 13528:2015 9.7 E_n with k = 1 u's)
  bool flagged = false;   // |E_n| > 1
};

struct DriftResult {
  uint64_t device_id = 0;
  RegistryCalibration from;  // The earlier of the device's last two calibrations.
  RegistryCalibration to;
  bool shared_inputs = false;  // The two share an input file (same SHA-256): cov != 0.
  std::vector<DriftConstant> constants;
};

struct DueDevice {
  uint64_t device_id = 0;
  int64_t calibration_id = 0;
  std::string certificate_id;
  std::string last_date_utc;  // The last calibration's fit date.
  std::string due_utc;        // last + interval
  double overdue_days = 0.0;  // now - due (> 0: due)
};

class Registry {
 public:
  // Opens `url` (see above), creating or migrating the schema. Errors (bad input, exit 2): a
  // file that is not a SQLite database or cannot be created, a server that cannot be reached,
  // a schema newer than this program.
  // The checks of ReadSchemaVersion come first (docs/registry.md "Schema"): a database with
  // tables but no schema_version (a foreign database) or a schema_version that is not exactly
  // one whole number from 1 to kRegistrySchemaVersion is refused, never migrated; an older
  // version is migrated in one transaction. A SQLite path must be absent or a regular file
  // (CheckUpdatableFile). Nothing throws.
  static Result<std::unique_ptr<Registry>> Open(const std::string& url);
  // For the queries: opens an existing registry without writing anything to it (a SQLite file
  // read-only, so a read-only file or directory can be queried; PostgreSQL in read-only
  // transactions); never creates or migrates. Errors (input): what Open refuses, an empty
  // database, a version older than this program's (the message says how to migrate it).
  static Result<std::unique_ptr<Registry>> OpenForQuery(const std::string& url);
  // The URL from --registry, else METRO_REGISTRY, else empty (no registry).
  static std::string UrlFromFlagOrEnvironment(const std::string& flag);
  // The SQLite file `url` names; empty for a server URL (postgresql://...) or an empty url.
  static std::string FileOf(const std::string& url);

  ~Registry();
  Registry(const Registry&) = delete;
  Registry& operator=(const Registry&) = delete;

  int schema_version() const { return version_; }
  const char* kind() const;  // "sqlite" or "postgresql"

  // Records each tag of `calibration` (constants, covariance, inputs' SHA-256, conformity,
  // station, operator) under `certificate_id`, the first 16 hex digits of the SHA-256 of the
  // calibration.json bytes (CalibrationCertificateId for a calibration as `fit` writes it;
  // the file's own hash for one read back, as its bytes are what identifies it). A tag recorded
  // before (same certificate id and sensor) is not duplicated. Returns the registry ids, in tag
  // order.
  Result<std::vector<int64_t>> RecordCalibration(const Calibration& calibration,
                                                 const std::string& certificate_id,
                                                 const RecordContext& context);
  // Records a blob made from tag `sensor` of `calibration` (recorded first if needed); from now
  // on that calibration belongs to the blob's device.
  Status RecordBlob(const Calibration& calibration, const std::string& certificate_id, int sensor,
                    const RegistryBlob& blob, const RecordContext& context);
  // The same for a push (successful or not; a failed push does not attach the calibration).
  Status RecordPush(const Calibration& calibration, const std::string& certificate_id, int sensor,
                    const RegistryPush& push, const RecordContext& context);

  // The device's calibrations, oldest first (by fit date, then registry id). Error when the
  // device is not in the registry.
  Result<std::vector<RegistryCalibration>> History(uint64_t device_id);
  // Change of every constant between the device's last two calibrations. Errors: the device
  // is unknown or has fewer than two calibrations.
  Result<DriftResult> Drift(uint64_t device_id);
  // Every device whose last calibration is older than `interval_days` at `now_utc` (ISO 8601),
  // and, with `all`, every device with its due date.
  Result<std::vector<DueDevice>> Due(double interval_days, const std::string& now_utc,
                                     bool all = false);
  // Every calibration (for export), oldest first.
  Result<std::vector<RegistryCalibration>> All();

 private:
  struct Impl;
  explicit Registry(std::unique_ptr<Impl> impl, int version);
  std::unique_ptr<Impl> impl_;
  int version_ = 0;
};

// JSON text of the queries (docs/registry.md; 2-space indent, keys sorted, no trailing
// newline): `history --json` ({"calibrations": [...], "device_id": ...}), `export --format
// json` ({"calibrations": [...], "schema_version": N}), `drift --json` and `due --json`
// ({"at_utc", "devices": [{"calibration_id", "certificate_id", "device_id", "due",
// "due_utc", "last_date_utc", "overdue_days"}], "interval_days"}).
std::string HistoryToJson(uint64_t device_id, const std::vector<RegistryCalibration>& history);
std::string ExportToJson(int schema_version, const std::vector<RegistryCalibration>& all);
std::string ToJson(const DriftResult& drift);
std::string DueToJson(const std::string& at_utc, double interval_days,
                      const std::vector<DueDevice>& due);
// `export --format csv` (docs/registry.md "Export"): a header, then one row per constant of each
// calibration: registry_id,certificate_id,sensor,date_utc,recorded_utc,station,operator,
// devices,constant,value,u,unit. A text field's control characters are escaped (a newline in a
// station name is written as \n; the JSON export keeps the text exactly), then the field is
// quoted when it holds a comma or a quote; devices are space-separated.
std::string ExportToCsv(const std::vector<RegistryCalibration>& all);

}  // namespace metro
