// Test helper: a throwaway PostgreSQL cluster for the registry tests (docs/registry.md
// "Tests"). initdb and pg_ctl (Debian's postgresql package, /usr/lib/postgresql/*/bin) make a
// cluster in a fresh temporary directory that listens only on a Unix socket there; as root
// the server runs as `nobody` (runuser), since PostgreSQL refuses to run as root. Started on
// first use, stopped and removed at exit. When the server binaries are absent the tests that
// need it are skipped with a visible warning, unless METRO_REQUIRE_POSTGRES=1 (CI), where the
// absence is a failure.
#pragma once

#include <glob.h>
#include <unistd.h>

#include <cstdlib>
#include <memory>
#include <random>
#include <string>

#include "registry/sql_backend.hpp"

namespace metro::testing {

class PostgresServer {
 public:
  // The running server, or nullptr with `why` set.
  static PostgresServer* Get(std::string* why) {
    static std::unique_ptr<PostgresServer> server = Start(&StartError());
    if (!server) *why = StartError();
    return server.get();
  }
  static bool Required() {
    const char* r = std::getenv("METRO_REQUIRE_POSTGRES");
    return r != nullptr && std::string(r) == "1";
  }

  // A new, empty database on the server; its libpq URI.
  std::string NewDatabase() {
    const std::string name = "metro_test_" + std::to_string(++databases_);
    Result<std::unique_ptr<registry_internal::SqlBackend>> admin =
        registry_internal::OpenPostgres(Uri("postgres"));
    if (admin.ok()) (void)admin.value()->Execute("CREATE DATABASE " + name, {}, nullptr);
    return Uri(name);
  }

  ~PostgresServer() {
    (void)std::system(
        (As() + bin_ + "/pg_ctl -D " + dir_ + "/data -m immediate -w stop >/dev/null 2>&1")
            .c_str());
    (void)std::system(("rm -rf " + dir_).c_str());
  }

 private:
  static std::string& StartError() {
    static std::string e;
    return e;
  }
  std::string As() const { return ::geteuid() == 0 ? "runuser -u nobody -- " : ""; }
  std::string Uri(const std::string& db) const {
    return "postgresql:///" + db + "?host=" + dir_ + "&port=" + std::to_string(port_) +
           "&user=metro";
  }

  static std::unique_ptr<PostgresServer> Start(std::string* why) {
    glob_t g{};
    std::string bin;
    if (::glob("/usr/lib/postgresql/*/bin/initdb", 0, nullptr, &g) == 0 && g.gl_pathc > 0) {
      bin = g.gl_pathv[g.gl_pathc - 1];
      bin = bin.substr(0, bin.rfind('/'));
    }
    globfree(&g);
    if (bin.empty()) {
      *why =
          "PostgreSQL server binaries not found (/usr/lib/postgresql/*/bin/initdb; Debian "
          "package postgresql): the PostgreSQL registry tests are SKIPPED";
      return nullptr;
    }
    if (::geteuid() == 0 && ::access("/usr/sbin/runuser", X_OK) != 0 &&
        ::access("/sbin/runuser", X_OK) != 0) {
      *why = "running as root without runuser: cannot start PostgreSQL as an unprivileged user";
      return nullptr;
    }
    char tmpl[] = "/tmp/metro-pg-XXXXXX";
    if (::mkdtemp(tmpl) == nullptr) {
      *why = "mkdtemp failed";
      return nullptr;
    }
    auto s = std::unique_ptr<PostgresServer>(new PostgresServer());
    s->bin_ = bin;
    s->dir_ = tmpl;
    if (::geteuid() == 0 && ::chown(tmpl, 65534, 65534) != 0) {
      *why = "cannot hand the cluster directory to nobody";
      return nullptr;
    }
    const std::string init = s->As() + bin + "/initdb -D " + s->dir_ + "/data -A trust -U metro " +
                             "--no-sync >" + s->dir_ + "/initdb.log 2>&1";
    if (std::system(init.c_str()) != 0) {
      *why = "initdb failed; see " + s->dir_ + "/initdb.log";
      return nullptr;
    }
    std::mt19937 rng(static_cast<unsigned>(::getpid()));
    for (int attempt = 0; attempt < 5; ++attempt) {
      s->port_ = 40000 + static_cast<int>(rng() % 20000);
      const std::string start = s->As() + bin + "/pg_ctl -D " + s->dir_ + "/data -l " + s->dir_ +
                                "/server.log -w -t 60 -o \"-k " + s->dir_ + " -h '' -p " +
                                std::to_string(s->port_) + " -F\" start >/dev/null 2>&1";
      if (std::system(start.c_str()) == 0) return s;
    }
    *why = "pg_ctl start failed; see " + s->dir_ + "/server.log";
    return nullptr;
  }

  PostgresServer() = default;
  std::string bin_;
  std::string dir_;
  int port_ = 0;
  int databases_ = 0;
};

}  // namespace metro::testing
