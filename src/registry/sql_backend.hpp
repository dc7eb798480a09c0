// The registry's two back ends behind one small interface: a SQLite file (SQLite C API) and a
// PostgreSQL database (libpq). SQL is written once with `?` placeholders; the PostgreSQL back
// end numbers them ($1, $2, ...). Values are bound as text or numbers and read back as text
// (numbers formatted exactly: shortest round-trip for doubles).
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "metro/core/status.hpp"

namespace metro::registry_internal {

using SqlValue = std::variant<std::nullptr_t, int64_t, double, std::string>;
using SqlRow = std::vector<std::optional<std::string>>;  // nullopt: SQL NULL

class SqlBackend {
 public:
  virtual ~SqlBackend() = default;

  // One statement with `?` placeholders; rows, when asked for, as text.
  virtual Status Execute(const std::string& sql, const std::vector<SqlValue>& params,
                         std::vector<SqlRow>* rows = nullptr) = 0;
  // Starts a write transaction that holds the database's write lock from its start (SQLite
  // BEGIN IMMEDIATE; PostgreSQL BEGIN plus an advisory lock when `exclusive`).
  virtual Status Begin(bool exclusive) = 0;
  virtual Status Commit() = 0;
  virtual void Rollback() = 0;
  // True when the last error was the other writers' lock or a serialization failure: the
  // transaction may be retried (SQLITE_BUSY / SQLITE_LOCKED; SQLSTATE 40001, 40P01).
  virtual bool LastErrorRetryable() const = 0;

  // One statement listing the database's own tables (one column, the name), schema_version
  // included; nothing of the engine's own (sqlite_*, the catalogs).
  virtual std::string TablesSql() const = 0;
  // Column type of an auto-numbered primary key.
  virtual std::string AutoIdColumn() const = 0;
  // "sqlite" or "postgresql".
  virtual const char* Kind() const = 0;
};

// Opens (creating when absent) a SQLite file: WAL journal, a busy timeout, foreign keys on.
// `read_only`: opened read-only and never created, nothing written (not even the journal
// mode); a WAL database in a directory the reader cannot write is opened as immutable when no
// write-ahead log is waiting beside it.
Result<std::unique_ptr<SqlBackend>> OpenSqlite(const std::string& path, int busy_timeout_ms,
                                               bool read_only = false);
// Connects to PostgreSQL with a libpq connection URI (postgresql://...); `read_only`: every
// transaction of the session is read-only (default_transaction_read_only).
Result<std::unique_ptr<SqlBackend>> OpenPostgres(const std::string& uri, bool read_only = false);

// A SQLite path or a postgresql:// URI (registry.hpp), opened.
Result<std::unique_ptr<SqlBackend>> OpenBackend(const std::string& url, bool read_only = false);

// A double as the shortest text that reads back to the same value.
std::string ExactDouble(double v);

}  // namespace metro::registry_internal
