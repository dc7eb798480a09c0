#include "metro/registry/registry.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <map>
#include <random>
#include <set>
#include <thread>

#include "calibration/calibration_json.hpp"
#include "core/json_text.hpp"
#include "metro/blob/blob.hpp"
#include "metro/calibration/calibration_io.hpp"
#include "metro/calibration/named_constants.hpp"
#include "metro/core/file.hpp"
#include "metro/core/terminal_text.hpp"
#include "metro/core/utc_time.hpp"
#include "schema.hpp"
#include "sql_backend.hpp"

namespace metro {

using nlohmann::json;
using registry_internal::SqlBackend;
using registry_internal::SqlRow;
using registry_internal::SqlValue;

namespace {

bool IsPostgresUrl(const std::string& url) {
  return url.rfind("postgresql://", 0) == 0 || url.rfind("postgres://", 0) == 0;
}

SqlValue Opt(const std::optional<double>& v) { return v ? SqlValue(*v) : SqlValue(nullptr); }

// The values of the rows of one table, each checked as it is read: a value metro does not
// write there (text where a number belongs, a number out of range, NULL in a column that has
// none, a device ID that is not 16 hex digits) is an input error naming the registry, the
// table, the column and the value; the first one is kept, the rest read as 0 or empty.
class Checked {
 public:
  Checked(const std::string& url, const char* table) : url_(url), table_(table) {}

  int64_t Integer(const std::optional<std::string>& v, const char* column, int64_t lo, int64_t hi) {
    if (!Present(v, column, "a whole number")) return 0;
    int64_t n = 0;
    const char* end = v->data() + v->size();
    const auto [at, ec] = std::from_chars(v->data(), end, n);
    if (ec != std::errc() || at != end || v->empty()) {
      Bad(column, *v, "a whole number");
      return 0;
    }
    if (n < lo || n > hi) {
      Bad(column, *v, fmt::format("a whole number from {} to {}", lo, hi));
      return 0;
    }
    return n;
  }
  double Number(const std::optional<std::string>& v, const char* column) {
    if (!Present(v, column, "a finite number")) return 0.0;
    return Parse(*v, column);
  }
  std::optional<double> OptNumber(const std::optional<std::string>& v, const char* column) {
    if (!v) return std::nullopt;
    return Parse(*v, column);
  }
  std::string Text(const std::optional<std::string>& v, const char* column) {
    return Present(v, column, "text") ? *v : std::string();
  }
  uint64_t Device(const std::optional<std::string>& v, const char* column) {
    if (!Present(v, column, "a device ID (16 hex digits)")) return 0;
    uint64_t id = 0;
    const char* end = v->data() + v->size();
    const auto [at, ec] = std::from_chars(v->data(), end, id, 16);
    if (v->size() != 16 || ec != std::errc() || at != end || (*v)[0] == '+' || (*v)[0] == '-') {
      Bad(column, *v, "a device ID (16 hex digits)");
      return 0;
    }
    return id;
  }
  template <typename T>
  T Named(const std::optional<std::string>& v, const char* column,
          std::optional<T> (*parse)(const std::string&), const char* expected) {
    if (!Present(v, column, expected)) return T{};
    const std::optional<T> parsed = parse(*v);
    if (!parsed) Bad(column, *v, expected);
    return parsed.value_or(T{});
  }
  // Ok, or the first bad value.
  Status status() const { return error_ ? Status(*error_) : Status::Ok(); }

 private:
  double Parse(const std::string& text, const char* column) {
    double d = 0.0;
    const char* end = text.data() + text.size();
    const auto [at, ec] = std::from_chars(text.data(), end, d);
    if (ec != std::errc() || at != end || text.empty() || !std::isfinite(d)) {
      Bad(column, text, "a finite number");
      return 0.0;
    }
    return d;
  }
  bool Present(const std::optional<std::string>& v, const char* column, const std::string& what) {
    if (v) return true;
    if (!error_) {
      error_ = MakeError(url_, 0, fmt::format("{}.{} is NULL; expected {}", table_, column, what));
    }
    return false;
  }
  void Bad(const char* column, const std::string& value, const std::string& expected) {
    if (error_) return;
    const std::string shown = value.size() > 40 ? value.substr(0, 40) + "..." : value;
    error_ = MakeError(
        url_, 0, fmt::format("{}.{} holds '{}'; expected {}", table_, column, shown, expected));
  }

  const std::string& url_;
  const char* table_;
  std::optional<Error> error_;
};

constexpr int64_t kMaxId = std::numeric_limits<int64_t>::max();
constexpr int64_t kMaxU32 = std::numeric_limits<uint32_t>::max();
constexpr int64_t kMaxSensor = std::numeric_limits<int>::max();

json SensorCovarianceJson(const SensorCalibration& c) {
  json cov = json::array();
  for (Eigen::Index r = 0; r < c.covariance.rows(); ++r) {
    json row = json::array();
    for (Eigen::Index k = 0; k < c.covariance.cols(); ++k) row.push_back(c.covariance(r, k));
    cov.push_back(row);
  }
  return {{"parameters", c.parameter_names}, {"covariance", cov}};
}

}  // namespace

struct Registry::Impl {
  std::unique_ptr<SqlBackend> db;
  std::string url;

  // Runs `body` in one transaction, retried (with a random pause) while other writers hold the
  // lock or a concurrent transaction conflicts. Nothing of a failed body stays behind.
  template <typename F>
  Status Transaction(F&& body) {
    std::minstd_rand jitter(
        static_cast<unsigned>(std::chrono::steady_clock::now().time_since_epoch().count()));
    for (int attempt = 0;; ++attempt) {
      Status s = db->Begin(/*exclusive=*/false);
      if (s.ok()) s = body();
      if (s.ok()) s = db->Commit();
      if (s.ok()) return s;
      const bool retry = db->LastErrorRetryable();
      db->Rollback();
      if (!retry || attempt >= 500) return s;
      std::this_thread::sleep_for(std::chrono::milliseconds(1 + jitter() % 20));
    }
  }

  // The registry id of tag `sensor` of `cal`, inserting it (with everything it carries) when
  // absent. Inside a transaction.
  Result<int64_t> EnsureCalibration(const Calibration& cal, const std::string& certificate_id,
                                    const TagCalibration& tag, const RecordContext& ctx) {
    std::vector<SqlRow> rows;
    json cov = json::object();
    if (tag.accel) cov["accel"] = SensorCovarianceJson(*tag.accel);
    if (tag.gyro) cov["gyro"] = SensorCovarianceJson(*tag.gyro);
    const std::string recorded = ctx.recorded_utc.empty() ? UtcIso8601Now() : ctx.recorded_utc;
    if (Status s = db->Execute(
            "INSERT INTO calibrations (certificate_id, sensor, date_utc, recorded_utc, "
            "tool_version, covariance_json, station, operator_name) VALUES (?, ?, ?, ?, ?, ?, ?, "
            "?) ON CONFLICT (certificate_id, sensor) DO NOTHING RETURNING id",
            {certificate_id, int64_t{tag.sensor}, cal.date_utc, recorded, cal.tool_version,
             JsonText(cov), ctx.station, ctx.operator_name},
            &rows);
        !s.ok()) {
      return s.error();
    }
    if (rows.empty()) {  // Recorded before: the same certificate and tag.
      if (Status s =
              db->Execute("SELECT id FROM calibrations WHERE certificate_id = ? AND sensor = ?",
                          {certificate_id, int64_t{tag.sensor}}, &rows);
          !s.ok()) {
        return s.error();
      }
      if (rows.empty()) return MakeError(url, 0, "calibration vanished while recording");
      return Id(rows[0][0], "calibrations");
    }
    Result<int64_t> inserted = Id(rows[0][0], "calibrations");
    if (!inserted.ok()) return inserted.error();
    const int64_t id = inserted.value();
    // A tags file named the tag's device (`calibrate fit --tags`, calibration.json's
    // `device_id`): the calibration belongs to that device from now on.
    if (tag.device_id) {
      if (Status s = Attach(blob::FormatDeviceId(*tag.device_id), id, "tags", recorded); !s.ok()) {
        return s.error();
      }
    }
    for (size_t i = 0; i < cal.inputs.size(); ++i) {
      if (Status s = db->Execute(
              "INSERT INTO calibration_inputs (calibration_id, position, path, sha256) VALUES "
              "(?, ?, ?, ?)",
              {id, static_cast<int64_t>(i), cal.inputs[i].path, cal.inputs[i].sha256});
          !s.ok()) {
        return s.error();
      }
    }
    const std::vector<NamedConstant> constants = NamedConstants(tag);
    for (size_t i = 0; i < constants.size(); ++i) {
      const NamedConstant& c = constants[i];
      if (Status s = db->Execute(
              "INSERT INTO constants (calibration_id, position, name, value, u, unit) VALUES "
              "(?, ?, ?, ?, ?, ?)",
              {id, static_cast<int64_t>(i), c.name, c.value, c.u, c.unit});
          !s.ok()) {
        return s.error();
      }
    }
    if (cal.conformity) {
      const ConformityStatement& st = *cal.conformity;
      int64_t position = 0;
      for (const ConformityEntry& e : st.entries) {
        if (e.sensor != tag.sensor) continue;
        if (Status s = db->Execute(
                "INSERT INTO conformity (calibration_id, position, constant, value, u, "
                "lower_limit, upper_limit, unit, acceptance_lower, acceptance_upper, "
                "p_conformance, decision, decision_rule, coverage_factor, max_consumer_risk) "
                "VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)",
                {id, position++, e.constant, e.value, e.u, Opt(e.lower), Opt(e.upper), e.unit,
                 Opt(e.acceptance_lower), Opt(e.acceptance_upper), e.p_conformance,
                 std::string(ConformityDecisionName(e.decision)),
                 std::string(DecisionRuleName(st.rule)), st.coverage_factor, st.max_consumer_risk});
            !s.ok()) {
          return s.error();
        }
      }
    }
    return id;
  }

  // A registry id read back (1 .. 2^63 - 1).
  Result<int64_t> Id(const std::optional<std::string>& v, const char* table) {
    Checked checked(url, table);
    const int64_t id = checked.Integer(v, "id", 1, kMaxId);
    if (Status s = checked.status(); !s.ok()) return s.error();
    return id;
  }

  Status Attach(const std::string& device, int64_t calibration_id, const char* source,
                const std::string& recorded) {
    return db->Execute(
        "INSERT INTO device_calibrations (device_id, calibration_id, source, recorded_utc) "
        "VALUES (?, ?, ?, ?) ON CONFLICT (device_id, calibration_id) DO NOTHING",
        {device, calibration_id, std::string(source), recorded});
  }

  Result<RegistryCalibration> Load(int64_t id, std::optional<uint64_t> device) {
    std::vector<SqlRow> rows;
    if (Status s =
            db->Execute("SELECT id, certificate_id, sensor, date_utc, recorded_utc, tool_version, "
                        "covariance_json, station, operator_name FROM calibrations WHERE id = ?",
                        {id}, &rows);
        !s.ok()) {
      return s.error();
    }
    if (rows.empty()) return MakeError(url, 0, fmt::format("no calibration {}", id));
    RegistryCalibration c;
    {
      Checked k(url, "calibrations");
      const SqlRow& r = rows[0];
      c.id = k.Integer(r[0], "id", 1, kMaxId);
      c.certificate_id = k.Text(r[1], "certificate_id");
      c.sensor = static_cast<int>(k.Integer(r[2], "sensor", 0, kMaxSensor));
      c.date_utc = k.Text(r[3], "date_utc");
      c.recorded_utc = k.Text(r[4], "recorded_utc");
      c.tool_version = k.Text(r[5], "tool_version");
      c.covariance_json = k.Text(r[6], "covariance_json");
      c.station = k.Text(r[7], "station");
      c.operator_name = k.Text(r[8], "operator_name");
      if (Status s = k.status(); !s.ok()) return s.error();
      if (Result<json> cov = ParseJsonText(c.covariance_json, "covariance_json");
          !cov.ok() || !cov.value().is_object()) {
        return MakeError(url, 0,
                         fmt::format("calibrations.covariance_json of calibration {} is not a "
                                     "JSON object{}",
                                     c.id, cov.ok() ? "" : ": " + cov.error().ToString()));
      }
    }
    rows.clear();
    if (Status s = db->Execute("SELECT path, sha256 FROM calibration_inputs WHERE calibration_id = "
                               "? ORDER BY position",
                               {id}, &rows);
        !s.ok()) {
      return s.error();
    }
    Checked inputs(url, "calibration_inputs");
    for (const SqlRow& x : rows) {
      c.inputs.push_back({inputs.Text(x[0], "path"), inputs.Text(x[1], "sha256")});
    }
    if (Status s = inputs.status(); !s.ok()) return s.error();
    rows.clear();
    if (Status s = db->Execute(
            "SELECT name, value, u, unit FROM constants WHERE calibration_id = ? ORDER BY position",
            {id}, &rows);
        !s.ok()) {
      return s.error();
    }
    Checked constants(url, "constants");
    for (const SqlRow& x : rows) {
      c.constants.push_back({constants.Text(x[0], "name"), constants.Number(x[1], "value"),
                             constants.Number(x[2], "u"), constants.Text(x[3], "unit")});
    }
    if (Status s = constants.status(); !s.ok()) return s.error();
    rows.clear();
    if (Status s = db->Execute(
            "SELECT constant, value, u, lower_limit, upper_limit, unit, acceptance_lower, "
            "acceptance_upper, p_conformance, decision, decision_rule, coverage_factor, "
            "max_consumer_risk FROM conformity WHERE calibration_id = ? ORDER BY position",
            {id}, &rows);
        !s.ok()) {
      return s.error();
    }
    Checked conformity(url, "conformity");
    for (const SqlRow& x : rows) {
      if (!c.conformity) {
        c.conformity = ConformityStatement{};
        c.conformity->rule = conformity.Named<DecisionRule>(
            x[10], "decision_rule", ParseDecisionRule, "simple, guarded or risk");
        c.conformity->coverage_factor = conformity.Number(x[11], "coverage_factor");
        c.conformity->max_consumer_risk = conformity.Number(x[12], "max_consumer_risk");
      }
      ConformityEntry e;
      e.sensor = c.sensor;
      e.constant = conformity.Text(x[0], "constant");
      e.value = conformity.Number(x[1], "value");
      e.u = conformity.Number(x[2], "u");
      e.lower = conformity.OptNumber(x[3], "lower_limit");
      e.upper = conformity.OptNumber(x[4], "upper_limit");
      e.unit = conformity.Text(x[5], "unit");
      e.acceptance_lower = conformity.OptNumber(x[6], "acceptance_lower");
      e.acceptance_upper = conformity.OptNumber(x[7], "acceptance_upper");
      e.p_conformance = conformity.Number(x[8], "p_conformance");
      e.decision = conformity.Named<ConformityDecision>(x[9], "decision", ParseConformityDecision,
                                                        "pass, fail or inconclusive");
      c.conformity->entries.push_back(std::move(e));
    }
    if (Status s = conformity.status(); !s.ok()) return s.error();
    rows.clear();
    if (Status s = db->Execute(
            "SELECT device_id FROM device_calibrations WHERE calibration_id = ? ORDER BY device_id",
            {id}, &rows);
        !s.ok()) {
      return s.error();
    }
    Checked devices(url, "device_calibrations");
    for (const SqlRow& x : rows) c.devices.push_back(devices.Device(x[0], "device_id"));
    if (Status s = devices.status(); !s.ok()) return s.error();
    if (!device) return c;
    const std::string dev = blob::FormatDeviceId(*device);
    rows.clear();
    if (Status s = db->Execute(
            "SELECT seq, crc, accel_t_valid_min_c, accel_t_valid_max_c, gyro_t_valid_min_c, "
            "gyro_t_valid_max_c, file, recorded_utc FROM blobs WHERE calibration_id = ? AND "
            "device_id = ? ORDER BY id",
            {id, dev}, &rows);
        !s.ok()) {
      return s.error();
    }
    Checked blobs(url, "blobs");
    for (const SqlRow& x : rows) {
      RegistryBlob b;
      b.device_id = *device;
      b.seq = static_cast<uint32_t>(blobs.Integer(x[0], "seq", 0, kMaxU32));
      b.crc = static_cast<uint32_t>(blobs.Integer(x[1], "crc", 0, kMaxU32));
      b.accel_t_valid_min_c = blobs.OptNumber(x[2], "accel_t_valid_min_c");
      b.accel_t_valid_max_c = blobs.OptNumber(x[3], "accel_t_valid_max_c");
      b.gyro_t_valid_min_c = blobs.OptNumber(x[4], "gyro_t_valid_min_c");
      b.gyro_t_valid_max_c = blobs.OptNumber(x[5], "gyro_t_valid_max_c");
      b.file = blobs.Text(x[6], "file");
      b.recorded_utc = blobs.Text(x[7], "recorded_utc");
      c.blobs.push_back(b);
    }
    if (Status s = blobs.status(); !s.ok()) return s.error();
    rows.clear();
    if (Status s = db->Execute(
            "SELECT port, ok, result, readback, recorded_utc FROM pushes WHERE calibration_id = "
            "? AND device_id = ? ORDER BY id",
            {id, dev}, &rows);
        !s.ok()) {
      return s.error();
    }
    Checked pushes(url, "pushes");
    for (const SqlRow& x : rows) {
      RegistryPush p;
      p.device_id = *device;
      p.port = pushes.Text(x[0], "port");
      p.ok = pushes.Integer(x[1], "ok", 0, 1) != 0;
      p.result = pushes.Text(x[2], "result");
      p.readback = pushes.Text(x[3], "readback");
      p.recorded_utc = pushes.Text(x[4], "recorded_utc");
      c.pushes.push_back(p);
    }
    if (Status s = pushes.status(); !s.ok()) return s.error();
    return c;
  }

  Result<std::vector<int64_t>> DeviceCalibrationIds(uint64_t device) {
    std::vector<SqlRow> rows;
    if (Status s =
            db->Execute("SELECT c.id FROM device_calibrations d JOIN calibrations c ON c.id = "
                        "d.calibration_id WHERE d.device_id = ? ORDER BY c.date_utc, c.id",
                        {blob::FormatDeviceId(device)}, &rows);
        !s.ok()) {
      return s.error();
    }
    if (rows.empty()) {
      return MakeError(url, 0,
                       fmt::format("device {} is not in the registry (no blob or push was "
                                   "recorded for it)",
                                   blob::FormatDeviceId(device)));
    }
    std::vector<int64_t> ids;
    for (const SqlRow& r : rows) {
      Result<int64_t> id = Id(r[0], "calibrations");
      if (!id.ok()) return id.error();
      ids.push_back(id.value());
    }
    return ids;
  }
};

Registry::Registry(std::unique_ptr<Impl> impl, int version)
    : impl_(std::move(impl)), version_(version) {}
Registry::~Registry() = default;

const char* Registry::kind() const { return impl_->db->Kind(); }

std::string Registry::UrlFromFlagOrEnvironment(const std::string& flag) {
  if (!flag.empty()) return flag;
  const char* env = std::getenv("METRO_REGISTRY");
  return env != nullptr ? std::string(env) : std::string();
}

namespace registry_internal {

Result<std::unique_ptr<SqlBackend>> OpenBackend(const std::string& url, bool read_only) {
  if (url.empty()) return MakeError("the registry URL is empty");
  if (IsPostgresUrl(url)) return registry_internal::OpenPostgres(url, read_only);
  if (url.find("://") != std::string::npos) {
    return MakeError(url, 0,
                     "unsupported registry URL; expected a file path (SQLite) or "
                     "postgresql://user@host/db");
  }
  // The registry is read and updated in place: never a device, a FIFO, a directory.
  if (Status s = CheckUpdatableFile(url); !s.ok()) return s.error();
  return registry_internal::OpenSqlite(url, /*busy_timeout_ms=*/10000, read_only);
}

}  // namespace registry_internal

std::string Registry::FileOf(const std::string& url) {
  if (url.empty() || url.find("://") != std::string::npos) return "";
  return url;
}

Result<std::unique_ptr<Registry>> Registry::Open(const std::string& url) {
  Result<std::unique_ptr<SqlBackend>> db = registry_internal::OpenBackend(url);
  if (!db.ok()) return db.error();
  auto impl = std::make_unique<Impl>();
  impl->db = std::move(db).value();
  impl->url = url;
  Result<int> v = registry_internal::Migrate(impl->db.get(), kRegistrySchemaVersion, url);
  if (!v.ok()) return v.error();
  return std::unique_ptr<Registry>(new Registry(std::move(impl), kRegistrySchemaVersion));
}

Result<std::unique_ptr<Registry>> Registry::OpenForQuery(const std::string& url) {
  Result<std::unique_ptr<SqlBackend>> db = registry_internal::OpenBackend(url, /*read_only=*/true);
  if (!db.ok()) return db.error();
  auto impl = std::make_unique<Impl>();
  impl->db = std::move(db).value();
  impl->url = url;
  Result<int> v = registry_internal::ReadSchemaVersion(impl->db.get(), url);
  if (!v.ok()) return v.error();
  if (v.value() == 0) {
    return MakeError(url, 0, "an empty database, not a metro registry (it has no tables)");
  }
  if (v.value() < kRegistrySchemaVersion) {
    return MakeError(url, 0,
                     fmt::format("the registry's schema is version {}, older than this program's "
                                 "{}; a query changes nothing: record into it once with this "
                                 "metro (calibrate fit, blob, push or apply --registry) to "
                                 "migrate it",
                                 v.value(), kRegistrySchemaVersion));
  }
  return std::unique_ptr<Registry>(new Registry(std::move(impl), v.value()));
}

Result<std::vector<int64_t>> Registry::RecordCalibration(const Calibration& calibration,
                                                         const std::string& certificate,
                                                         const RecordContext& context) {
  std::vector<int64_t> ids;
  Status s = impl_->Transaction([&]() -> Status {
    ids.clear();
    for (const TagCalibration& tag : calibration.tags) {
      Result<int64_t> id = impl_->EnsureCalibration(calibration, certificate, tag, context);
      if (!id.ok()) return id.error();
      ids.push_back(id.value());
    }
    return Status::Ok();
  });
  if (!s.ok()) return s.error();
  return ids;
}

Status Registry::RecordBlob(const Calibration& calibration, const std::string& certificate,
                            int sensor, const RegistryBlob& blob, const RecordContext& context) {
  const TagCalibration* tag = calibration.FindTag(sensor);
  if (tag == nullptr) return MakeError(fmt::format("no tag sensor {} in the calibration", sensor));
  const std::string recorded =
      context.recorded_utc.empty() ? UtcIso8601Now() : context.recorded_utc;
  const std::string dev = blob::FormatDeviceId(blob.device_id);
  return impl_->Transaction([&]() -> Status {
    Result<int64_t> id = impl_->EnsureCalibration(calibration, certificate, *tag, context);
    if (!id.ok()) return id.error();
    if (Status s = impl_->db->Execute(
            "INSERT INTO blobs (device_id, calibration_id, seq, crc, accel_t_valid_min_c, "
            "accel_t_valid_max_c, gyro_t_valid_min_c, gyro_t_valid_max_c, file, recorded_utc) "
            "VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?)",
            {dev, id.value(), int64_t{blob.seq}, int64_t{blob.crc}, Opt(blob.accel_t_valid_min_c),
             Opt(blob.accel_t_valid_max_c), Opt(blob.gyro_t_valid_min_c),
             Opt(blob.gyro_t_valid_max_c), blob.file, recorded});
        !s.ok()) {
      return s;
    }
    return impl_->Attach(dev, id.value(), "blob", recorded);
  });
}

Status Registry::RecordPush(const Calibration& calibration, const std::string& certificate,
                            int sensor, const RegistryPush& push, const RecordContext& context) {
  const TagCalibration* tag = calibration.FindTag(sensor);
  if (tag == nullptr) return MakeError(fmt::format("no tag sensor {} in the calibration", sensor));
  const std::string recorded =
      context.recorded_utc.empty() ? UtcIso8601Now() : context.recorded_utc;
  const std::string dev = blob::FormatDeviceId(push.device_id);
  return impl_->Transaction([&]() -> Status {
    Result<int64_t> id = impl_->EnsureCalibration(calibration, certificate, *tag, context);
    if (!id.ok()) return id.error();
    if (Status s = impl_->db->Execute(
            "INSERT INTO pushes (device_id, calibration_id, port, ok, result, readback, "
            "recorded_utc) VALUES (?, ?, ?, ?, ?, ?, ?)",
            {dev, id.value(), push.port, int64_t{push.ok ? 1 : 0}, push.result, push.readback,
             recorded});
        !s.ok()) {
      return s;
    }
    // Only a push the tag accepted puts the calibration on it.
    return push.ok ? impl_->Attach(dev, id.value(), "push", recorded) : Status::Ok();
  });
}

Result<std::vector<RegistryCalibration>> Registry::History(uint64_t device_id) {
  Result<std::vector<int64_t>> ids = impl_->DeviceCalibrationIds(device_id);
  if (!ids.ok()) return ids.error();
  std::vector<RegistryCalibration> out;
  for (int64_t id : ids.value()) {
    Result<RegistryCalibration> c = impl_->Load(id, device_id);
    if (!c.ok()) return c.error();
    out.push_back(std::move(c).value());
  }
  return out;
}

Result<DriftResult> Registry::Drift(uint64_t device_id) {
  Result<std::vector<int64_t>> ids = impl_->DeviceCalibrationIds(device_id);
  if (!ids.ok()) return ids.error();
  if (ids.value().size() < 2) {
    return MakeError(impl_->url, 0,
                     fmt::format("device {} has {} calibration; drift needs two",
                                 blob::FormatDeviceId(device_id), ids.value().size()));
  }
  const size_t n = ids.value().size();
  Result<RegistryCalibration> from = impl_->Load(ids.value()[n - 2], std::nullopt);
  if (!from.ok()) return from.error();
  Result<RegistryCalibration> to = impl_->Load(ids.value()[n - 1], std::nullopt);
  if (!to.ok()) return to.error();
  DriftResult d;
  d.device_id = device_id;
  d.from = std::move(from).value();
  d.to = std::move(to).value();
  std::set<std::string> hashes;
  for (const InputFile& f : d.from.inputs) hashes.insert(f.sha256);
  for (const InputFile& f : d.to.inputs)
    d.shared_inputs = d.shared_inputs || hashes.count(f.sha256) > 0;
  std::map<std::string, const RegistryConstant*> before;
  for (const RegistryConstant& c : d.from.constants) before[c.name] = &c;
  for (const RegistryConstant& c : d.to.constants) {
    auto it = before.find(c.name);
    if (it == before.end() || it->second->unit != c.unit) continue;  // Not comparable.
    DriftConstant k;
    k.name = c.name;
    k.unit = c.unit;
    k.from = it->second->value;
    k.to = c.value;
    k.change = k.to - k.from;
    // Two calibrations from separate records are independent: cov = 0 (docs/registry.md).
    k.u_change = std::sqrt(it->second->u * it->second->u + c.u * c.u);
    // E_n with standard (k = 1) uncertainties: |E_n| > 1 is a change larger than its u.
    k.en = k.u_change > 0 ? k.change / k.u_change : (k.change == 0 ? 0.0 : HUGE_VAL);
    k.flagged = std::abs(k.en) > 1.0;
    d.constants.push_back(k);
  }
  return d;
}

Result<std::vector<DueDevice>> Registry::Due(double interval_days, const std::string& now_utc,
                                             bool all) {
  const std::optional<std::time_t> now = ParseUtcIso8601(now_utc);
  if (!now) return MakeError(fmt::format("'{}' is not an ISO 8601 UTC time", now_utc));
  std::vector<SqlRow> rows;
  if (Status s = impl_->db->Execute(
          "SELECT d.device_id, c.id, c.certificate_id, c.date_utc FROM device_calibrations d "
          "JOIN calibrations c ON c.id = d.calibration_id ORDER BY d.device_id, c.date_utc, c.id",
          {}, &rows);
      !s.ok()) {
    return s.error();
  }
  Checked checked(impl_->url, "device_calibrations");
  std::map<uint64_t, const SqlRow*> last;
  for (const SqlRow& r : rows) last[checked.Device(r[0], "device_id")] = &r;
  if (Status s = checked.status(); !s.ok()) return s.error();
  std::vector<DueDevice> out;
  Checked calibrations(impl_->url, "calibrations");
  for (const auto& [dev, r] : last) {
    DueDevice d;
    d.device_id = dev;
    d.calibration_id = calibrations.Integer((*r)[1], "id", 1, kMaxId);
    d.certificate_id = calibrations.Text((*r)[2], "certificate_id");
    d.last_date_utc = calibrations.Text((*r)[3], "date_utc");
    if (Status s = calibrations.status(); !s.ok()) return s.error();
    const std::optional<std::time_t> last_t = ParseUtcIso8601(d.last_date_utc);
    if (!last_t) {
      return MakeError(impl_->url, 0,
                       fmt::format("calibration {} has date_utc '{}', not ISO 8601 UTC",
                                   d.calibration_id, d.last_date_utc));
    }
    const double due_s = static_cast<double>(*last_t) + interval_days * 86400.0;
    d.due_utc = UtcIso8601(static_cast<std::time_t>(std::llround(due_s)));
    d.overdue_days = (static_cast<double>(*now) - due_s) / 86400.0;
    if (all || d.overdue_days > 0) out.push_back(d);
  }
  return out;
}

Result<std::vector<RegistryCalibration>> Registry::All() {
  std::vector<SqlRow> rows;
  if (Status s = impl_->db->Execute("SELECT id FROM calibrations ORDER BY date_utc, id", {}, &rows);
      !s.ok()) {
    return s.error();
  }
  std::vector<RegistryCalibration> out;
  for (const SqlRow& r : rows) {
    Result<int64_t> id = impl_->Id(r[0], "calibrations");
    if (!id.ok()) return id.error();
    Result<RegistryCalibration> c = impl_->Load(id.value(), std::nullopt);
    if (!c.ok()) return c.error();
    out.push_back(std::move(c).value());
  }
  return out;
}

namespace {

json RegistryCalibrationValue(const RegistryCalibration& c) {
  json j;
  j["id"] = c.id;
  j["certificate_id"] = c.certificate_id;
  j["sensor"] = c.sensor;
  j["date_utc"] = c.date_utc;
  j["recorded_utc"] = c.recorded_utc;
  j["tool_version"] = c.tool_version;
  j["station"] = c.station;
  j["operator"] = c.operator_name;
  json devices = json::array();
  for (uint64_t d : c.devices) devices.push_back(blob::FormatDeviceId(d));
  j["devices"] = devices;
  json inputs = json::array();
  for (const InputFile& f : c.inputs) inputs.push_back({{"path", f.path}, {"sha256", f.sha256}});
  j["inputs"] = inputs;
  json constants = json::array();
  for (const RegistryConstant& k : c.constants) {
    constants.push_back({{"name", k.name}, {"value", k.value}, {"u", k.u}, {"unit", k.unit}});
  }
  j["constants"] = constants;
  Result<json> cov = ParseJsonText(c.covariance_json, "covariance_json");
  j["covariance"] = cov.ok() ? cov.value() : json::object();
  if (c.conformity) {
    j["conformity_rule"] = ConformityRuleToJson(*c.conformity);
    j["conformity"] = ConformityEntriesToJson(*c.conformity);
  } else {
    j["conformity"] = json::array();
  }
  json blobs = json::array();
  for (const RegistryBlob& b : c.blobs) {
    json x;
    x["device_id"] = blob::FormatDeviceId(b.device_id);
    x["seq"] = b.seq;
    x["crc32"] = fmt::format("0x{:08X}", b.crc);
    auto opt = [](const std::optional<double>& v) { return v ? json(*v) : json(nullptr); };
    x["accel_t_valid_min_c"] = opt(b.accel_t_valid_min_c);
    x["accel_t_valid_max_c"] = opt(b.accel_t_valid_max_c);
    x["gyro_t_valid_min_c"] = opt(b.gyro_t_valid_min_c);
    x["gyro_t_valid_max_c"] = opt(b.gyro_t_valid_max_c);
    x["file"] = b.file;
    x["recorded_utc"] = b.recorded_utc;
    blobs.push_back(x);
  }
  j["blobs"] = blobs;
  json pushes = json::array();
  for (const RegistryPush& p : c.pushes) {
    pushes.push_back({{"device_id", blob::FormatDeviceId(p.device_id)},
                      {"port", p.port},
                      {"ok", p.ok},
                      {"result", p.result},
                      {"readback", p.readback},
                      {"recorded_utc", p.recorded_utc}});
  }
  j["pushes"] = pushes;
  return j;
}

json DriftValue(const DriftResult& d) {
  json j;
  j["device_id"] = blob::FormatDeviceId(d.device_id);
  auto ref = [](const RegistryCalibration& c) {
    return json{{"id", c.id}, {"certificate_id", c.certificate_id}, {"date_utc", c.date_utc}};
  };
  j["from"] = ref(d.from);
  j["to"] = ref(d.to);
  j["shared_inputs"] = d.shared_inputs;
  json constants = json::array();
  for (const DriftConstant& k : d.constants) {
    constants.push_back({{"name", k.name},
                         {"unit", k.unit},
                         {"from", k.from},
                         {"to", k.to},
                         {"change", k.change},
                         {"u_change", k.u_change},
                         {"en", std::isfinite(k.en) ? json(k.en) : json(nullptr)},
                         {"flagged", k.flagged}});
  }
  j["constants"] = constants;
  return j;
}

}  // namespace

std::string HistoryToJson(uint64_t device_id, const std::vector<RegistryCalibration>& history) {
  json j;
  j["device_id"] = blob::FormatDeviceId(device_id);
  j["calibrations"] = json::array();
  for (const RegistryCalibration& c : history)
    j["calibrations"].push_back(RegistryCalibrationValue(c));
  return JsonText(j, 2);
}

std::string ExportToJson(int schema_version, const std::vector<RegistryCalibration>& all) {
  json j;
  j["schema_version"] = schema_version;
  j["calibrations"] = json::array();
  for (const RegistryCalibration& c : all) j["calibrations"].push_back(RegistryCalibrationValue(c));
  return JsonText(j, 2);
}

std::string ToJson(const DriftResult& drift) { return JsonText(DriftValue(drift), 2); }

std::string DueToJson(const std::string& at_utc, double interval_days,
                      const std::vector<DueDevice>& due) {
  json j;
  j["at_utc"] = at_utc;
  j["interval_days"] = interval_days;
  j["devices"] = json::array();
  for (const DueDevice& d : due) {
    j["devices"].push_back({{"device_id", blob::FormatDeviceId(d.device_id)},
                            {"calibration_id", d.calibration_id},
                            {"certificate_id", d.certificate_id},
                            {"last_date_utc", d.last_date_utc},
                            {"due_utc", d.due_utc},
                            {"overdue_days", d.overdue_days},
                            {"due", d.overdue_days > 0}});
  }
  return JsonText(j, 2);
}

namespace {

std::string CsvField(const std::string& data) {
  const std::string field = EscapeControlChars(data);
  if (field.find_first_of(",\"") == std::string::npos) return field;
  std::string out = "\"";
  for (char c : field) out += c == '"' ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}

}  // namespace

std::string ExportToCsv(const std::vector<RegistryCalibration>& all) {
  std::string text =
      "registry_id,certificate_id,sensor,date_utc,recorded_utc,station,operator,devices,"
      "constant,value,u,unit\n";
  for (const RegistryCalibration& c : all) {
    std::string devices;
    for (uint64_t d : c.devices) devices += (devices.empty() ? "" : " ") + blob::FormatDeviceId(d);
    for (const RegistryConstant& k : c.constants) {
      text += fmt::format("{},{},{},{},{},{},{},{},{},{},{},{}\n", c.id, CsvField(c.certificate_id),
                          c.sensor, CsvField(c.date_utc), CsvField(c.recorded_utc),
                          CsvField(c.station), CsvField(c.operator_name), devices, CsvField(k.name),
                          k.value, k.u, CsvField(k.unit));
    }
  }
  return text;
}

}  // namespace metro
