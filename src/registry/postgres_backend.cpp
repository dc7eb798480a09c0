// The PostgreSQL back end (libpq, libpq-dev).
#include <fmt/format.h>
#include <libpq-fe.h>

#include <regex>

#include "sql_backend.hpp"

namespace metro::registry_internal {
namespace {

// `?` -> $1, $2, ... outside quoted literals.
std::string NumberPlaceholders(const std::string& sql) {
  std::string out;
  int n = 0;
  bool quoted = false;
  for (char c : sql) {
    if (c == '\'') quoted = !quoted;
    if (c == '?' && !quoted) {
      out += "$" + std::to_string(++n);
    } else {
      out += c;
    }
  }
  return out;
}

// The URI without its password, for messages.
std::string Redacted(const std::string& uri) {
  return std::regex_replace(uri, std::regex("(://[^:/@]*):[^@/]*@"), "$1:***@");
}

void IgnoreNotice(void*, const char*) {}

class PostgresBackend : public SqlBackend {
 public:
  PostgresBackend(PGconn* conn, std::string uri) : conn_(conn), uri_(std::move(uri)) {}
  ~PostgresBackend() override { PQfinish(conn_); }

  Status Execute(const std::string& sql, const std::vector<SqlValue>& params,
                 std::vector<SqlRow>* rows) override {
    last_sqlstate_.clear();
    std::vector<std::string> text(params.size());
    std::vector<const char*> values(params.size(), nullptr);
    for (size_t i = 0; i < params.size(); ++i) {
      const SqlValue& v = params[i];
      if (std::holds_alternative<std::nullptr_t>(v)) continue;
      if (const int64_t* n = std::get_if<int64_t>(&v)) {
        text[i] = std::to_string(*n);
      } else if (const double* d = std::get_if<double>(&v)) {
        text[i] = ExactDouble(*d);
      } else {
        text[i] = std::get<std::string>(v);
      }
      values[i] = text[i].c_str();
    }
    const std::string numbered = NumberPlaceholders(sql);
    PGresult* res = PQexecParams(conn_, numbered.c_str(), static_cast<int>(params.size()), nullptr,
                                 values.data(), nullptr, nullptr, 0);
    const ExecStatusType st = PQresultStatus(res);
    if (st != PGRES_COMMAND_OK && st != PGRES_TUPLES_OK) {
      const char* state = PQresultErrorField(res, PG_DIAG_SQLSTATE);
      last_sqlstate_ = state != nullptr ? state : "";
      std::string message = PQresultErrorMessage(res);
      while (!message.empty() && (message.back() == '\n' || message.back() == ' ')) {
        message.pop_back();
      }
      if (message.empty()) message = PQerrorMessage(conn_);
      PQclear(res);
      return MakeError(Redacted(uri_), 0, fmt::format("PostgreSQL: {}", message));
    }
    if (rows != nullptr && st == PGRES_TUPLES_OK) {
      const int nr = PQntuples(res);
      const int nc = PQnfields(res);
      for (int r = 0; r < nr; ++r) {
        SqlRow row;
        for (int c = 0; c < nc; ++c) {
          if (PQgetisnull(res, r, c)) {
            row.push_back(std::nullopt);
          } else {
            row.push_back(
                std::string(PQgetvalue(res, r, c), static_cast<size_t>(PQgetlength(res, r, c))));
          }
        }
        rows->push_back(std::move(row));
      }
    }
    PQclear(res);
    return Status::Ok();
  }

  Status Begin(bool exclusive) override {
    if (Status s = Execute("BEGIN", {}, nullptr); !s.ok()) return s;
    // The schema migration: one process at a time (a transaction-scoped advisory lock).
    if (exclusive) return Execute("SELECT pg_advisory_xact_lock(727106)", {}, nullptr);
    return Status::Ok();
  }
  Status Commit() override { return Execute("COMMIT", {}, nullptr); }
  void Rollback() override {
    if (PQtransactionStatus(conn_) != PQTRANS_IDLE) {
      PGresult* r = PQexec(conn_, "ROLLBACK");
      PQclear(r);
    }
  }
  bool LastErrorRetryable() const override {
    // serialization_failure, deadlock_detected, unique_violation of a concurrent first insert
    return last_sqlstate_ == "40001" || last_sqlstate_ == "40P01" || last_sqlstate_ == "23505";
  }
  std::string TablesSql() const override {
    return "SELECT table_name FROM information_schema.tables WHERE table_schema = "
           "current_schema() AND table_type = 'BASE TABLE' ORDER BY table_name";
  }
  std::string AutoIdColumn() const override { return "BIGSERIAL PRIMARY KEY"; }
  const char* Kind() const override { return "postgresql"; }

 private:
  PGconn* conn_;
  std::string uri_;
  std::string last_sqlstate_;
};

}  // namespace

Result<std::unique_ptr<SqlBackend>> OpenPostgres(const std::string& uri, bool read_only) {
  PGconn* conn = PQconnectdb(uri.c_str());
  if (conn == nullptr || PQstatus(conn) != CONNECTION_OK) {
    std::string why = conn != nullptr ? PQerrorMessage(conn) : "out of memory";
    while (!why.empty() && (why.back() == '\n' || why.back() == ' ')) why.pop_back();
    PQfinish(conn);
    return MakeError(Redacted(uri), 0,
                     fmt::format("cannot connect to the PostgreSQL registry: {}", why));
  }
  PQsetNoticeProcessor(conn, IgnoreNotice, nullptr);
  auto backend = std::make_unique<PostgresBackend>(conn, uri);
  if (read_only) {
    if (Status s = backend->Execute("SET default_transaction_read_only = on", {}, nullptr);
        !s.ok()) {
      return s.error();
    }
  }
  return std::unique_ptr<SqlBackend>(std::move(backend));
}

}  // namespace metro::registry_internal
