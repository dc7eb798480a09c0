// The SQLite back end (SQLite C API, libsqlite3-dev).
#include <fmt/format.h>
#include <sqlite3.h>
#include <sys/stat.h>

#include <cctype>

#include "sql_backend.hpp"

namespace metro::registry_internal {
namespace {

class SqliteBackend : public SqlBackend {
 public:
  SqliteBackend(sqlite3* db, std::string path) : db_(db), path_(std::move(path)) {}
  ~SqliteBackend() override { sqlite3_close_v2(db_); }

  Status Execute(const std::string& sql, const std::vector<SqlValue>& params,
                 std::vector<SqlRow>* rows) override {
    last_code_ = SQLITE_OK;
    sqlite3_stmt* stmt = nullptr;
    int rc = sqlite3_prepare_v2(db_, sql.c_str(), static_cast<int>(sql.size()), &stmt, nullptr);
    if (rc != SQLITE_OK) return Fail(rc, sql);
    for (size_t i = 0; i < params.size(); ++i) {
      const int at = static_cast<int>(i + 1);
      const SqlValue& v = params[i];
      if (std::holds_alternative<std::nullptr_t>(v)) {
        rc = sqlite3_bind_null(stmt, at);
      } else if (const int64_t* n = std::get_if<int64_t>(&v)) {
        rc = sqlite3_bind_int64(stmt, at, *n);
      } else if (const double* d = std::get_if<double>(&v)) {
        rc = sqlite3_bind_double(stmt, at, *d);
      } else {
        const std::string& s = std::get<std::string>(v);
        rc = sqlite3_bind_text(stmt, at, s.data(), static_cast<int>(s.size()), SQLITE_TRANSIENT);
      }
      if (rc != SQLITE_OK) {
        sqlite3_finalize(stmt);
        return Fail(rc, sql);
      }
    }
    while ((rc = sqlite3_step(stmt)) == SQLITE_ROW) {
      if (rows == nullptr) continue;
      SqlRow row;
      const int n = sqlite3_column_count(stmt);
      for (int c = 0; c < n; ++c) {
        switch (sqlite3_column_type(stmt, c)) {
          case SQLITE_NULL:
            row.push_back(std::nullopt);
            break;
          case SQLITE_FLOAT:  // Exactly: sqlite3_column_text keeps only 15 digits.
            row.push_back(ExactDouble(sqlite3_column_double(stmt, c)));
            break;
          default: {
            const unsigned char* t = sqlite3_column_text(stmt, c);
            row.push_back(std::string(reinterpret_cast<const char*>(t),
                                      static_cast<size_t>(sqlite3_column_bytes(stmt, c))));
          }
        }
      }
      rows->push_back(std::move(row));
    }
    sqlite3_finalize(stmt);
    if (rc != SQLITE_DONE) return Fail(rc, sql);
    return Status::Ok();
  }

  Status Begin(bool /*exclusive*/) override {
    // IMMEDIATE takes the write lock now, so two writers never both read and then collide
    // on the upgrade (which SQLite cannot resolve by waiting).
    return Execute("BEGIN IMMEDIATE", {}, nullptr);
  }
  Status Commit() override { return Execute("COMMIT", {}, nullptr); }
  void Rollback() override {
    if (!sqlite3_get_autocommit(db_)) sqlite3_exec(db_, "ROLLBACK", nullptr, nullptr, nullptr);
  }
  bool LastErrorRetryable() const override {
    return (last_code_ & 0xff) == SQLITE_BUSY || (last_code_ & 0xff) == SQLITE_LOCKED;
  }
  std::string TablesSql() const override {
    return "SELECT name FROM sqlite_master WHERE type = 'table' AND name NOT LIKE 'sqlite\\_%' "
           "ESCAPE '\\' ORDER BY name";
  }
  std::string AutoIdColumn() const override { return "INTEGER PRIMARY KEY AUTOINCREMENT"; }
  int last_code() const { return last_code_; }
  const char* Kind() const override { return "sqlite"; }

 private:
  Status Fail(int rc, const std::string& sql) {
    last_code_ = rc;
    std::string first = sql.substr(0, sql.find('('));
    if (first.size() > 60) first = first.substr(0, 60) + "...";
    return MakeError(path_, 0, fmt::format("SQLite: {} ({})", sqlite3_errmsg(db_), first));
  }

  sqlite3* db_;
  std::string path_;
  int last_code_ = SQLITE_OK;
};

// A SQLite URI filename for `path` (https://sqlite.org/uri.html): every byte but letters,
// digits and / . _ - ~ percent-encoded, so ? # % in a name stay part of it.
std::string FileUri(const std::string& path, const char* query) {
  std::string p = path;
  while (p.rfind("//", 0) == 0) p.erase(0, 1);  // "//x" would name a host.
  std::string out = "file:";
  for (unsigned char c : p) {
    if (std::isalnum(c) || c == '/' || c == '.' || c == '_' || c == '-' || c == '~') {
      out += static_cast<char>(c);
    } else {
      out += fmt::format("%{:02X}", c);
    }
  }
  return out + "?" + query;
}

Result<std::unique_ptr<SqliteBackend>> OpenSqliteConnection(const std::string& name,
                                                            const std::string& path, int flags,
                                                            int busy_timeout_ms) {
  sqlite3* db = nullptr;
  const int rc = sqlite3_open_v2(name.c_str(), &db, flags | SQLITE_OPEN_NOMUTEX, nullptr);
  if (rc != SQLITE_OK) {
    std::string why = db != nullptr ? sqlite3_errmsg(db) : sqlite3_errstr(rc);
    sqlite3_close_v2(db);
    return MakeError(path, 0, fmt::format("cannot open the SQLite registry: {}", why));
  }
  sqlite3_extended_result_codes(db, 1);
  sqlite3_busy_timeout(db, busy_timeout_ms);
  return std::make_unique<SqliteBackend>(db, path);
}

}  // namespace

Result<std::unique_ptr<SqlBackend>> OpenSqlite(const std::string& path, int busy_timeout_ms,
                                               bool read_only) {
  if (read_only) {
    // Nothing is written: no journal mode, no pragma that changes the file.
    for (const char* query : {"mode=ro", "mode=ro&immutable=1"}) {
      Result<std::unique_ptr<SqliteBackend>> opened = OpenSqliteConnection(
          FileUri(path, query), path, SQLITE_OPEN_READONLY | SQLITE_OPEN_URI, busy_timeout_ms);
      if (!opened.ok()) return opened.error();
      std::unique_ptr<SqliteBackend> backend = std::move(opened).value();
      Status s = backend->Execute("SELECT count(*) FROM sqlite_master", {}, nullptr);
      if (s.ok()) return std::unique_ptr<SqlBackend>(std::move(backend));
      // A WAL database whose directory the reader cannot write (no -shm can be made): read
      // as immutable, unless a write-ahead log with commits not yet in the file is beside it.
      const int code = backend->last_code() & 0xff;
      struct stat wal {};
      const bool wal_waiting = ::stat((path + "-wal").c_str(), &wal) == 0 && wal.st_size > 0;
      if ((code != SQLITE_READONLY && code != SQLITE_CANTOPEN) || wal_waiting) {
        return MakeError(path, 0, "cannot open the SQLite registry: " + s.error().message);
      }
    }
    return MakeError(path, 0, "cannot open the SQLite registry read-only");
  }
  Result<std::unique_ptr<SqliteBackend>> opened =
      OpenSqliteConnection(path, path, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE, busy_timeout_ms);
  if (!opened.ok()) return opened.error();
  std::unique_ptr<SqliteBackend> backend = std::move(opened).value();
  // A file that is not a database fails here ("file is not a database").
  std::vector<SqlRow> mode;
  if (Status s = backend->Execute("PRAGMA journal_mode=WAL", {}, &mode); !s.ok()) {
    return MakeError(path, 0, "cannot open the SQLite registry: " + s.error().message);
  }
  if (Status s = backend->Execute("PRAGMA foreign_keys=ON", {}, nullptr); !s.ok()) return s;
  if (Status s = backend->Execute("PRAGMA synchronous=NORMAL", {}, nullptr); !s.ok()) return s;
  return std::unique_ptr<SqlBackend>(std::move(backend));
}

std::string ExactDouble(double v) { return fmt::format("{}", v); }

}  // namespace metro::registry_internal
