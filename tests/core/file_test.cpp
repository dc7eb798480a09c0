#include "metro/core/file.hpp"

#include <sys/resource.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <utility>
#include <vector>

namespace metro {
namespace {

TEST_CASE("SHA-256 of known strings", "[core]") {
  // FIPS 180-2 appendix B.1 and the empty string.
  CHECK(Sha256Hex("abc") == "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  CHECK(Sha256Hex("") == "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
}

TEST_CASE("SHA-256 hashed in chunks is the one-shot digest and reports its progress", "[core]") {
  // FIPS 180-2 appendix B.2 and B.3 (one million 'a').
  const std::string b2 = "abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq";
  const std::string b3(1000000, 'a');
  for (const size_t chunk : {size_t{1}, size_t{7}, size_t{64}, size_t{4096}, size_t{1} << 22}) {
    for (const auto& [text, digest] :
         {std::pair<const std::string&, const char*>{
              b2, "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1"},
          std::pair<const std::string&, const char*>{
              b3, "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0"}}) {
      if (chunk == 1 && text.size() > 1000) continue;  // A million calls prove nothing more.
      std::vector<size_t> reported;
      CHECK(Sha256Hex(text, chunk, [&](size_t n) { reported.push_back(n); }) == digest);
      REQUIRE(reported.size() == (text.size() + chunk - 1) / chunk);
      CHECK(reported.back() == text.size());
      for (size_t i = 0; i + 1 < reported.size(); ++i) CHECK(reported[i] == (i + 1) * chunk);
    }
  }
  size_t calls = 0;
  CHECK(Sha256Hex("", 0, [&](size_t) { ++calls; }) ==
        "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
  CHECK(calls == 0);
  CHECK(Sha256Hex("abc", 0, nullptr) ==
        "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
}

TEST_CASE("WriteFileAtomically replaces a file and ReadFile reads it back", "[core]") {
  const std::string path = "metro_file_test_" + std::to_string(::getpid()) + ".txt";
  REQUIRE(WriteFileAtomically(path, "first").ok());
  REQUIRE(WriteFileAtomically(path, "second\n").ok());
  auto back = ReadFile(path);
  REQUIRE(back.ok());
  CHECK(back.value() == "second\n");
  CHECK(IsSameFile(path, "./" + path));
  std::remove(path.c_str());
}

TEST_CASE("ReadFile reads at most its bound: a larger file before reading, a device at it",
          "[core][security]") {
  const std::string path = "metro_file_bounded_" + std::to_string(::getpid()) + ".txt";
  REQUIRE(WriteFileAtomically(path, std::string(100, 'x')).ok());
  REQUIRE(ReadFile(path, 100).ok());
  CHECK(ReadFile(path, 100).value().size() == 100);
  Result<std::string> r = ReadFile(path, 99);
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().file == path);
  CHECK_THAT(r.error().message, Catch::StartsWith("100 bytes: more than 99 bytes"));
  // An endless device stops at the bound (--columns-file /dev/zero reached 11 GB, issue #37),
  // the default bound included.
  r = ReadFile("/dev/zero", 1 << 20);
  REQUIRE_FALSE(r.ok());
  CHECK_THAT(r.error().message, Catch::StartsWith("still reading: more than 1048576 bytes"));
  r = ReadFile("/dev/zero");
  REQUIRE_FALSE(r.ok());
  CHECK_THAT(r.error().message,
             Catch::Contains("more than " + std::to_string(kMaxDocumentBytes) + " bytes"));
  std::remove(path.c_str());
}

TEST_CASE("File errors name the path", "[core]") {
  auto missing = ReadFile("/nonexistent/metro/x.csv");
  REQUIRE_FALSE(missing.ok());
  CHECK(missing.error().ToString().find("/nonexistent/metro/x.csv") != std::string::npos);
  auto dir_write = WriteFileAtomically("/nonexistent-dir/out.json", "{}");
  REQUIRE_FALSE(dir_write.ok());
  CHECK(dir_write.error().ToString().find("/nonexistent-dir/out.json") != std::string::npos);
}

// A fresh directory for the output tests, removed at the end.
struct OutDir {
  OutDir() {
    static int counter = 0;
    path = "metro_file_out_" + std::to_string(::getpid()) + "_" + std::to_string(counter++);
    std::filesystem::remove_all(path);
    std::filesystem::create_directories(path);
  }
  ~OutDir() { std::filesystem::remove_all(path); }
  std::string operator/(const std::string& name) const { return path + "/" + name; }
  // Nothing but `names` in the directory (no temporary left behind).
  size_t Entries() const {
    size_t n = 0;
    for ([[maybe_unused]] const auto& e : std::filesystem::directory_iterator(path)) ++n;
    return n;
  }
  std::string path;
};

std::string Contents(const std::string& path) {
  Result<std::string> text = ReadFile(path);
  REQUIRE(text.ok());
  return text.value();
}

mode_t Mode(const std::string& path) {
  struct stat st {};
  REQUIRE(::stat(path.c_str(), &st) == 0);
  return st.st_mode & 07777;
}

TEST_CASE("A replaced file keeps its mode; a new file gets 0666 minus the umask",
          "[core][security]") {
  OutDir d;
  const std::string path = d / "report.json";
  REQUIRE(WriteFileAtomically(path, "one").ok());
  const mode_t mask = ::umask(022);
  ::umask(mask);
  CHECK(Mode(path) == (0666 & ~mask));
  for (const mode_t mode : {mode_t{0600}, mode_t{0640}, mode_t{0604}}) {
    REQUIRE(::chmod(path.c_str(), mode) == 0);
    REQUIRE(WriteFileAtomically(path, "two").ok());
    CHECK(Mode(path) == mode);
  }
  CHECK(Contents(path) == "two");
  CHECK(d.Entries() == 1);
}

TEST_CASE("An output name of 254 and 255 characters can be written and replaced",
          "[core][security]") {
  OutDir d;
  for (const size_t length : {size_t{254}, size_t{255}}) {
    const std::string path = d / std::string(length, 'n');
    INFO(length);
    REQUIRE(WriteFileAtomically(path, "a").ok());
    REQUIRE(WriteFileAtomically(path, "b").ok());
    CHECK(Contents(path) == "b");
  }
  CHECK(d.Entries() == 2);
}

TEST_CASE("Outputs refuse devices, FIFOs, directories and /dev; the file is untouched",
          "[core][security]") {
  OutDir d;
  const std::string fifo = d / "fifo";
  REQUIRE(::mkfifo(fifo.c_str(), 0600) == 0);
  const std::string tail =
      ": metro writes an output to a new file and renames it into place, which would replace "
      "it; name a regular file (or - for stdout, redirected where you want it)";
  struct Case {
    std::string path, what;
  };
  for (const Case& c :
       {Case{"/dev/null", "is a character device"}, Case{"/dev/full", "is a character device"},
        Case{fifo, "is a FIFO (named pipe)"}, Case{d.path, "is a directory"},
        Case{"/dev/shm/metro_never_written", "is in /dev"},
        Case{"/proc/self/metro", "is in /proc"}}) {
    INFO(c.path);
    Status s = CheckReplaceableFile(c.path);
    REQUIRE_FALSE(s.ok());
    CHECK(s.error().message == c.path + " " + c.what + tail);
    Status w = WriteFileAtomically(c.path, "x");
    REQUIRE_FALSE(w.ok());
    CHECK(w.error().message == s.error().message);
  }
  struct stat st {};
  REQUIRE(::stat("/dev/null", &st) == 0);
  CHECK(S_ISCHR(st.st_mode));
  REQUIRE(::stat(fifo.c_str(), &st) == 0);
  CHECK(S_ISFIFO(st.st_mode));
  Status missing = CheckReplaceableFile(d / "no/such/x.json");
  REQUIRE_FALSE(missing.ok());
  CHECK(missing.error().message == d / "no/such/x.json" + ": the directory " + d / "no/such" +
                                       " does not exist: create it first");
  CHECK(d.Entries() == 1);
}

TEST_CASE("A file updated in place must be a regular file or absent", "[core][security]") {
  OutDir d;
  const std::string fifo = d / "fifo";
  REQUIRE(::mkfifo(fifo.c_str(), 0600) == 0);
  const std::string sock = d / "sock";
  const int fd = ::socket(AF_UNIX, SOCK_STREAM, 0);
  REQUIRE(fd >= 0);
  sockaddr_un addr{};
  addr.sun_family = AF_UNIX;
  std::strncpy(addr.sun_path, sock.c_str(), sizeof addr.sun_path - 1);
  REQUIRE(::bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) == 0);
  const std::string tail =
      ": metro reads and updates this file in place (a database); name a regular file";
  struct Case {
    std::string path, what;
  };
  for (const Case& c :
       {Case{"/dev/null", "is a character device"}, Case{fifo, "is a FIFO (named pipe)"},
        Case{sock, "is a socket"}, Case{d.path, "is a directory"},
        Case{"/proc/self/x.sqlite", "is in /proc"}}) {
    INFO(c.path);
    Status s = CheckUpdatableFile(c.path);
    REQUIRE_FALSE(s.ok());
    CHECK(s.error().message == c.path + " " + c.what + tail);
  }
  ::close(fd);
  REQUIRE(WriteFileAtomically(d / "reg.sqlite", "x").ok());
  CHECK(CheckUpdatableFile(d / "reg.sqlite").ok());
  CHECK(CheckUpdatableFile(d / "new.sqlite").ok());
  std::filesystem::create_symlink(std::filesystem::absolute(d / "reg.sqlite"), d / "link.sqlite");
  CHECK(CheckUpdatableFile(d / "link.sqlite").ok());
  CHECK_FALSE(CheckUpdatableFile(d / "no/such/r.sqlite").ok());
}

// No .metro-XXXXXX temporary in `dir`.
bool NoTemporary(const std::string& dir) {
  for (const auto& e : std::filesystem::directory_iterator(dir)) {
    if (e.path().filename().string().rfind(".metro-", 0) == 0) return false;
  }
  return true;
}

// A child process that, with or without InstallInterruptCleanup, starts replacing `path`
// (and holds a registered temporary `plot` as a plot does), says so on a pipe and waits for
// a signal. Returns the child's wait status after `signal` was sent.
int InterruptedWriter(const std::string& path, const std::string& plot, bool install, int signal) {
  int ready[2];
  REQUIRE(::pipe(ready) == 0);
  const pid_t pid = ::fork();
  REQUIRE(pid >= 0);
  if (pid == 0) {
    ::close(ready[0]);
    // As a program started from a terminal (a test runner may ignore some signals).
    for (int s : {SIGINT, SIGTERM, SIGHUP}) ::signal(s, SIG_DFL);
    if (install) InstallInterruptCleanup();
    AtomicFileWriter writer(path);
    if (!writer.Open().ok() || !writer.Write(std::string(1 << 20, 'n')).ok()) ::_exit(3);
    std::FILE* f = std::fopen(plot.c_str(), "w");
    if (f == nullptr) ::_exit(4);
    std::fclose(f);
    RemoveOnInterrupt plot_cleanup(plot);
    if (::write(ready[1], "r", 1) != 1) ::_exit(5);
    for (;;) ::pause();
  }
  ::close(ready[1]);
  char c = 0;
  REQUIRE(::read(ready[0], &c, 1) == 1);
  ::close(ready[0]);
  REQUIRE(::kill(pid, signal) == 0);
  int status = 0;
  REQUIRE(::waitpid(pid, &status, 0) == pid);
  return status;
}

TEST_CASE("SIGINT and SIGTERM while writing remove the temporaries and keep the old file",
          "[core][security]") {
  OutDir d;
  const std::string path = d / "r.json";
  const std::string plot = d / "metro_plot_test";
  REQUIRE(WriteFileAtomically(path, "old").ok());
  for (int signal : {SIGINT, SIGTERM, SIGHUP}) {
    INFO(signal);
    const int status = InterruptedWriter(path, plot, true, signal);
    // The process ended by the signal, as without the handler.
    REQUIRE(WIFSIGNALED(status));
    CHECK(WTERMSIG(status) == signal);
    CHECK(NoTemporary(d.path));
    CHECK_FALSE(std::filesystem::exists(plot));
    CHECK(Contents(path) == "old");
  }
  // Without the handler both temporaries stay behind: what the handler removes.
  const int status = InterruptedWriter(path, plot, false, SIGTERM);
  REQUIRE(WIFSIGNALED(status));
  CHECK_FALSE(NoTemporary(d.path));
  CHECK(std::filesystem::exists(plot));
  CHECK(Contents(path) == "old");
}

TEST_CASE("Past the file-size limit a write fails with EFBIG, not SIGXFSZ", "[core][security]") {
  OutDir d;
  const std::string path = d / "big.bin";
  REQUIRE(WriteFileAtomically(path, "old").ok());
  for (bool install : {true, false}) {
    INFO(install);
    const pid_t pid = ::fork();
    REQUIRE(pid >= 0);
    if (pid == 0) {
      ::signal(SIGXFSZ, SIG_DFL);
      if (install) InstallInterruptCleanup();
      rlimit limit{};
      limit.rlim_cur = limit.rlim_max = 64 * 1024;
      if (::setrlimit(RLIMIT_FSIZE, &limit) != 0) ::_exit(3);
      Status s = WriteFileAtomically(path, std::string(1 << 20, 'x'));
      const bool efbig = !s.ok() && s.error().kind == ErrorKind::kIo &&
                         s.error().message.find(std::strerror(EFBIG)) != std::string::npos;
      ::_exit(efbig ? 0 : 4);
    }
    int status = 0;
    REQUIRE(::waitpid(pid, &status, 0) == pid);
    if (install) {
      REQUIRE(WIFEXITED(status));
      CHECK(WEXITSTATUS(status) == 0);
      CHECK(NoTemporary(d.path));
    } else {
      REQUIRE(WIFSIGNALED(status));
      CHECK(WTERMSIG(status) == SIGXFSZ);
    }
    CHECK(Contents(path) == "old");
  }
  // The killed writer could not remove its temporary; the one that saw EFBIG did.
  for (const auto& e : std::filesystem::directory_iterator(d.path)) {
    if (e.path().filename().string().rfind(".metro-", 0) == 0) std::filesystem::remove(e.path());
  }
}

TEST_CASE("WriteFilesAtomically replaces every file or none", "[core][security]") {
  OutDir d;
  const std::string json = d / "r.json", html = d / "r.html";
  REQUIRE(WriteFileAtomically(json, "old json").ok());
  REQUIRE(WriteFileAtomically(html, "old html").ok());
  // The second cannot be written (its directory is gone): the first is not replaced.
  Status s = WriteFilesAtomically({{json, "new json"}, {d / "gone/r.html", "new html"}});
  REQUIRE_FALSE(s.ok());
  CHECK(Contents(json) == "old json");
  CHECK(d.Entries() == 2);  // No temporary left.
  REQUIRE(WriteFilesAtomically({{json, "new json"}, {html, "new html"}}).ok());
  CHECK(Contents(json) == "new json");
  CHECK(Contents(html) == "new html");
  CHECK(d.Entries() == 2);
}

TEST_CASE("IsSameFile sees through symlinks, hard links, and paths not written yet",
          "[core][security]") {
  namespace fs = std::filesystem;
  OutDir d;
  const std::string file = d / "f.json";
  REQUIRE(WriteFileAtomically(file, "x").ok());
  fs::create_symlink(fs::absolute(file), d / "link.json");
  fs::create_hard_link(file, d / "hard.json");
  CHECK(IsSameFile(file, d / "link.json"));
  CHECK(IsSameFile(d / "hard.json", d / "link.json"));
  CHECK_FALSE(IsSameFile(file, d / "other.json"));
  fs::create_directories(d / "sub");
  fs::create_directory_symlink(fs::absolute(d / "sub"), d / "sublink");
  CHECK(IsSameFile(d / "sub/new.json", d / "sublink/../sub/./new.json"));
  CHECK(IsSameFile(d / "sub/new.json", d / "sublink/new.json"));
  CHECK_FALSE(IsSameFile(d / "sub/new.json", d / "sub/new.html"));
}

TEST_CASE("Writing through a symlink replaces its target and keeps the link", "[core][security]") {
  namespace fs = std::filesystem;
  OutDir d;
  fs::create_directories(d / "archive");
  const std::string target = d / "archive/r1.json";
  REQUIRE(WriteFileAtomically(target, "old").ok());
  fs::create_symlink(fs::absolute(target), d / "latest.json");
  REQUIRE(WriteFileAtomically(d / "latest.json", "new").ok());
  CHECK(fs::is_symlink(d / "latest.json"));
  CHECK(Contents(target) == "new");
}

}  // namespace
}  // namespace metro
