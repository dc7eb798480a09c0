// Standard input as a session file (io/stdin_input.hpp): the bytes piped in come back
// whole through path(), from memory, a temporary file or stdin's own file, whatever the
// reads look like (partial, interrupted, non-blocking, empty); a terminal is refused.
#include "io/stdin_input.hpp"

#include <dirent.h>
#include <fcntl.h>
#include <signal.h>
#include <stdlib.h>
#include <sys/stat.h>
#include <sys/time.h>
#include <unistd.h>

#include <atomic>
#include <catch2/catch.hpp>
#include <chrono>
#include <cstdio>
#include <string>
#include <thread>

#include "metro/core/file.hpp"
#include "metro/io/session_io.hpp"
#include "support/temp_file.hpp"

namespace metro::internal {
namespace {

using testing::TempFile;

// `size` bytes of a pattern that no shifted or truncated copy matches.
std::string Pattern(size_t size) {
  std::string s(size, '\0');
  uint32_t x = 12345;
  for (char& c : s) {
    x = x * 1664525u + 1013904223u;
    c = static_cast<char>('a' + (x >> 24) % 26);
  }
  return s;
}

// A pipe whose write end a thread fills with `data`, `chunks` writes `pause` apart, then
// closes. The read end is the caller's.
class FedPipe {
 public:
  FedPipe(std::string data, size_t chunks = 1,
          std::chrono::milliseconds pause = std::chrono::milliseconds(0))
      : data_(std::move(data)) {
    REQUIRE(::pipe2(fds_, O_CLOEXEC) == 0);
    // The writer blocks SIGALRM, so the interrupted-read test's signals hit the reader, and
    // SIGPIPE, so a reader that gave up makes its write fail instead of killing the tests.
    sigset_t block, old;
    sigemptyset(&block);
    sigaddset(&block, SIGALRM);
    sigaddset(&block, SIGPIPE);
    pthread_sigmask(SIG_BLOCK, &block, &old);
    writer_ = std::thread([this, chunks, pause] {
      const size_t step = (data_.size() + chunks - 1) / (chunks == 0 ? 1 : chunks);
      for (size_t at = 0; at < data_.size(); at += step) {
        if (at > 0) std::this_thread::sleep_for(pause);
        size_t left = std::min(step, data_.size() - at);
        const char* p = data_.data() + at;
        while (left > 0) {
          const ssize_t n = ::write(fds_[1], p, left);
          if (n < 0) break;
          p += n;
          left -= static_cast<size_t>(n);
        }
      }
      ::close(fds_[1]);
    });
    pthread_sigmask(SIG_SETMASK, &old, nullptr);
  }
  FedPipe(const FedPipe&) = delete;
  FedPipe& operator=(const FedPipe&) = delete;
  ~FedPipe() {
    ::close(fds_[0]);
    if (writer_.joinable()) writer_.join();
  }
  int read_fd() const { return fds_[0]; }

 private:
  std::string data_;
  int fds_[2] = {-1, -1};
  std::thread writer_;
};

std::string ReadBack(const StdinFile& f) {
  Result<std::string> text = ReadFile(f.path());
  REQUIRE(text.ok());
  return text.value();
}

// Names of the entries of `dir` other than . and ..
std::vector<std::string> Entries(const std::string& dir) {
  std::vector<std::string> names;
  DIR* d = ::opendir(dir.c_str());
  if (d == nullptr) return names;
  while (const dirent* e = ::readdir(d)) {
    const std::string name = e->d_name;
    if (name != "." && name != "..") names.push_back(name);
  }
  ::closedir(d);
  return names;
}

// Makes `fd` this process's standard input while it lives.
class StdinRedirect {
 public:
  explicit StdinRedirect(int fd) : saved_(::fcntl(STDIN_FILENO, F_DUPFD_CLOEXEC, 0)) {
    ok_ = ::dup2(fd, STDIN_FILENO) == STDIN_FILENO;
  }
  StdinRedirect(const StdinRedirect&) = delete;
  StdinRedirect& operator=(const StdinRedirect&) = delete;
  ~StdinRedirect() {
    if (saved_ >= 0) {
      ::dup2(saved_, STDIN_FILENO);
      ::close(saved_);
    } else {
      ::close(STDIN_FILENO);
    }
  }
  bool ok() const { return ok_; }

 private:
  int saved_ = -1;
  bool ok_ = false;
};

std::atomic<int> alarms{0};
void CountAlarm(int) { ++alarms; }

const std::string kSession =
    "t_s,sensor,pitch_deg,roll_deg\n"
    "0.0,2,1.25,-0.5\n"
    "0.1,2,1.5,-0.25\n"
    "0.2,2,1.0,-0.75\n"
    "0.0,7,10.0,3.0\n"
    "0.1,7,10.5,3.5\n";

TEST_CASE("A piped stdin comes back whole through path(), larger than the pipe", "[io][stdin]") {
  const std::string data = Pattern(3'000'017);  // Many pipe buffers and 1 MiB chunks.
  FedPipe pipe(data, 7, std::chrono::milliseconds(2));
  StdinCopyOptions options;
  options.source_fd = pipe.read_fd();
  Result<StdinFile> copy = CopyStdinToFile(options);
  REQUIRE(copy.ok());
  const StdinFile& f = copy.value();
  CHECK(f.size_bytes() == static_cast<int64_t>(data.size()));
  CHECK(f.path() == "/proc/self/fd/" + std::to_string(f.fd()));
  CHECK((f.storage() == StdinStorage::kMemfd || f.storage() == StdinStorage::kTmpfile));
  CHECK(ReadBack(f) == data);
  // The hash the loaders record is the hash of the bytes piped in.
  Result<std::string> digest = Sha256File(f.path());
  REQUIRE(digest.ok());
  CHECK(digest.value() == Sha256Hex(data));
}

TEST_CASE("The in-memory copy is sealed: its bytes cannot change", "[io][stdin]") {
  FedPipe pipe("abc\n");
  StdinCopyOptions options;
  options.source_fd = pipe.read_fd();
  Result<StdinFile> copy = CopyStdinToFile(options);
  REQUIRE(copy.ok());
  if (copy.value().storage() != StdinStorage::kMemfd) {
    WARN("no memfd_create here: nothing to check");
    return;
  }
  CHECK(::write(copy.value().fd(), "x", 1) == -1);
  CHECK(::ftruncate(copy.value().fd(), 0) == -1);
  CHECK(ReadBack(copy.value()) == "abc\n");
}

TEST_CASE("Without memfd the copy is a temporary file that leaves nothing behind", "[io][stdin]") {
  char dir_template[] = "metro_stdin_dir_XXXXXX";
  REQUIRE(::mkdtemp(dir_template) != nullptr);
  const std::string dir = dir_template;
  const std::string data = Pattern(200'000);
  {
    FedPipe pipe(data, 3);
    StdinCopyOptions options;
    options.source_fd = pipe.read_fd();
    options.try_memfd = false;
    options.tmp_dir = dir;
    Result<StdinFile> copy = CopyStdinToFile(options);
    REQUIRE(copy.ok());
    CHECK(copy.value().storage() == StdinStorage::kTmpfile);
    CHECK(ReadBack(copy.value()) == data);
    // With /proc (Linux) the file is unlinked at once; without, it goes on destruction.
    if (copy.value().path().rfind("/proc/self/fd/", 0) == 0) CHECK(Entries(dir).empty());
  }
  CHECK(Entries(dir).empty());
  ::rmdir(dir.c_str());
}

TEST_CASE("The temporary-file fallback names the directory it cannot use", "[io][stdin]") {
  FedPipe pipe("abc\n");
  StdinCopyOptions options;
  options.source_fd = pipe.read_fd();
  options.try_memfd = false;
  options.tmp_dir = "metro_no_such_dir/deeper";
  Result<StdinFile> copy = CopyStdinToFile(options);
  REQUIRE_FALSE(copy.ok());
  CHECK(copy.error().ToString() ==
        "<stdin>: cannot make a temporary file in metro_no_such_dir/deeper to hold stdin; name "
        "the file instead of piping it: No such file or directory");
}

TEST_CASE("An empty stdin is an empty file, which the loader calls empty", "[io][stdin]") {
  FedPipe pipe("");
  StdinCopyOptions options;
  options.source_fd = pipe.read_fd();
  Result<StdinFile> copy = CopyStdinToFile(options);
  REQUIRE(copy.ok());
  CHECK(copy.value().size_bytes() == 0);
  CHECK(ReadBack(copy.value()).empty());
  Result<Session> session = LoadSession(copy.value().path());
  REQUIRE_FALSE(session.ok());
  CHECK(session.error().message.find("empty file") != std::string::npos);
}

TEST_CASE("A terminal on stdin is refused", "[io][stdin]") {
  const int master = ::posix_openpt(O_RDWR | O_NOCTTY);
  if (master < 0) {
    WARN("no pseudo-terminals here: nothing to check");
    return;
  }
  REQUIRE(::grantpt(master) == 0);
  REQUIRE(::unlockpt(master) == 0);
  const int slave = ::open(::ptsname(master), O_RDWR | O_NOCTTY | O_CLOEXEC);
  REQUIRE(slave >= 0);
  StdinCopyOptions options;
  options.source_fd = slave;
  Result<StdinFile> copy = CopyStdinToFile(options);
  REQUIRE_FALSE(copy.ok());
  CHECK(copy.error().ToString() ==
        "reading a session from stdin, but stdin is a terminal: pipe a file in or name it");
  ::close(slave);
  ::close(master);
}

TEST_CASE("A closed stdin is an error, not a read of our own copy", "[io][stdin]") {
  const int fd = ::dup(STDERR_FILENO);
  REQUIRE(fd >= 0);
  ::close(fd);
  StdinCopyOptions options;
  options.source_fd = fd;
  Result<StdinFile> copy = CopyStdinToFile(options);
  REQUIRE_FALSE(copy.ok());
  CHECK(copy.error().ToString() == "<stdin>: stdin is closed: pipe a file in or name it");
}

TEST_CASE("The default source is the process's stdin", "[io][stdin]") {
  FedPipe pipe(kSession);
  StdinRedirect redirect(pipe.read_fd());
  REQUIRE(redirect.ok());
  Result<StdinFile> copy = CopyStdinToFile();
  REQUIRE(copy.ok());
  CHECK(ReadBack(copy.value()) == kSession);
}

TEST_CASE("A regular file on stdin is used in place; read from its offset otherwise",
          "[io][stdin]") {
  TempFile file(kSession);
  const int fd = ::open(file.path().c_str(), O_RDONLY | O_CLOEXEC);
  REQUIRE(fd >= 0);
  StdinCopyOptions options;
  options.source_fd = fd;
  {
    Result<StdinFile> copy = CopyStdinToFile(options);
    REQUIRE(copy.ok());
    CHECK(copy.value().storage() == StdinStorage::kStdinItself);
    CHECK(copy.value().size_bytes() == static_cast<int64_t>(kSession.size()));
    CHECK(IsSameFile(copy.value().path(), file.path()));
    CHECK(ReadBack(copy.value()) == kSession);
  }
  // A shell's `(read header; characterize -) < s.csv`: stdin is what is left to read.
  REQUIRE(::lseek(fd, 10, SEEK_SET) == 10);
  Result<StdinFile> rest = CopyStdinToFile(options);
  REQUIRE(rest.ok());
  CHECK(rest.value().storage() != StdinStorage::kStdinItself);
  CHECK(ReadBack(rest.value()) == kSession.substr(10));
  ::close(fd);
}

TEST_CASE("Reads interrupted by signals are retried", "[io][stdin]") {
  // SIGALRM every 200 us without SA_RESTART, while the writer pauses between chunks: the
  // reader's blocked read() returns EINTR.
  struct sigaction action {
  }, old_action{};
  action.sa_handler = CountAlarm;
  sigemptyset(&action.sa_mask);
  action.sa_flags = 0;
  REQUIRE(::sigaction(SIGALRM, &action, &old_action) == 0);
  itimerval timer{}, old_timer{};
  timer.it_interval.tv_usec = 200;
  timer.it_value.tv_usec = 200;
  alarms = 0;
  const std::string data = Pattern(300'000);
  Result<StdinFile> copy = MakeError("not run");
  {
    FedPipe pipe(data, 20, std::chrono::milliseconds(3));
    REQUIRE(::setitimer(ITIMER_REAL, &timer, &old_timer) == 0);
    StdinCopyOptions options;
    options.source_fd = pipe.read_fd();
    copy = CopyStdinToFile(options);
    ::setitimer(ITIMER_REAL, &old_timer, nullptr);
  }
  // A last alarm still on its way lands on our handler, not on the default (terminate).
  std::this_thread::sleep_for(std::chrono::milliseconds(10));
  ::sigaction(SIGALRM, &old_action, nullptr);
  CHECK(alarms > 0);
  REQUIRE(copy.ok());
  CHECK(ReadBack(copy.value()) == data);
}

TEST_CASE("A non-blocking stdin is waited on, not taken as ended", "[io][stdin]") {
  const std::string data = Pattern(100'000);
  FedPipe pipe(data, 10, std::chrono::milliseconds(3));
  REQUIRE(::fcntl(pipe.read_fd(), F_SETFL, O_NONBLOCK) == 0);
  StdinCopyOptions options;
  options.source_fd = pipe.read_fd();
  Result<StdinFile> copy = CopyStdinToFile(options);
  REQUIRE(copy.ok());
  CHECK(ReadBack(copy.value()) == data);
}

TEST_CASE("A moved StdinFile hands over its descriptor", "[io][stdin]") {
  FedPipe pipe("abc\n");
  StdinCopyOptions options;
  options.source_fd = pipe.read_fd();
  Result<StdinFile> copy = CopyStdinToFile(options);
  REQUIRE(copy.ok());
  StdinFile a = std::move(copy).value();
  const int fd = a.fd();
  StdinFile b = std::move(a);
  CHECK(a.fd() == -1);  // NOLINT(bugprone-use-after-move): the moved-from state is specified.
  CHECK(a.path().empty());
  CHECK(b.fd() == fd);
  CHECK(ReadBack(b) == "abc\n");
  b = StdinFile();
  CHECK(::fcntl(fd, F_GETFD) == -1);  // Closed.
}

TEST_CASE("A session piped in loads as the same session as its file", "[io][stdin]") {
  TempFile file(kSession);
  FedPipe pipe(kSession);
  StdinCopyOptions options;
  options.source_fd = pipe.read_fd();
  Result<StdinFile> copy = CopyStdinToFile(options);
  REQUIRE(copy.ok());
  Result<Session> from_file = LoadSession(file.path());
  Result<Session> from_stdin = LoadSession(copy.value().path());
  REQUIRE(from_file.ok());
  REQUIRE(from_stdin.ok());
  CHECK(from_stdin.value().sha256 == from_file.value().sha256);
  CHECK(from_stdin.value().sha256 == Sha256Hex(kSession));
  REQUIRE(from_stdin.value().tags.size() == 2);
  CHECK(from_stdin.value().tags[0].t_s == from_file.value().tags[0].t_s);
  CHECK(from_stdin.value().tags[1].size() == 2);
}

TEST_CASE("A stream longer than its cap is refused at the cap, naming it", "[io][stdin]") {
  FedPipe pipe(Pattern(5000), 5);
  StdinCopyOptions options;
  options.source_fd = pipe.read_fd();
  options.max_bytes = 4096;
  Result<StdinFile> copy = CopyStdinToFile(options);
  REQUIRE_FALSE(copy.ok());
  CHECK(copy.error().file == kStdinDisplayName);
  CHECK_THAT(copy.error().message, Catch::Contains("more than 4096 bytes"));
  CHECK_THAT(copy.error().message, Catch::Contains(kMaxStreamBytesVariable));
  // At the cap exactly, the stream is whole.
  FedPipe exact(Pattern(4096), 3);
  options.source_fd = exact.read_fd();
  Result<StdinFile> whole = CopyStdinToFile(options);
  REQUIRE(whole.ok());
  CHECK(ReadBack(whole.value()) == Pattern(4096));
}

TEST_CASE("Binary data on a stream is refused on its first bytes, not at the cap", "[io][stdin]") {
  std::string data = kSession;
  data[10] = '\0';
  FedPipe pipe(data);
  StdinCopyOptions options;
  options.source_fd = pipe.read_fd();
  options.display_name = "/dev/zero";
  Result<StdinFile> copy = CopyStdinToFile(options);
  REQUIRE_FALSE(copy.ok());
  CHECK(copy.error().file == "/dev/zero");
  CHECK_THAT(copy.error().message, Catch::Contains("binary data (NUL bytes)"));
}

TEST_CASE("METRO_MAX_STREAM_BYTES sets the cap; a value that is no byte count is refused",
          "[io][stdin]") {
  struct Restore {
    ~Restore() { ::unsetenv(kMaxStreamBytesVariable); }
  } restore;
  ::unsetenv(kMaxStreamBytesVariable);
  REQUIRE(MaxStreamBytes().ok());
  CHECK(MaxStreamBytes().value() == kDefaultMaxStreamBytes);
  ::setenv(kMaxStreamBytesVariable, "123456", 1);
  REQUIRE(MaxStreamBytes().ok());
  CHECK(MaxStreamBytes().value() == 123456);
  for (const char* bad : {"1e9", "-5", "0", "12 MB", "99999999999999999999"}) {
    ::setenv(kMaxStreamBytesVariable, bad, 1);
    Result<int64_t> cap = MaxStreamBytes();
    REQUIRE_FALSE(cap.ok());
    CHECK_THAT(cap.error().message, Catch::Contains(std::string("'") + bad + "'"));
  }
}

TEST_CASE("A FIFO named as the session is read as a stream and keeps its name", "[io][stdin]") {
  testing::ScratchFolder folder("metro_fifo_session");
  const std::string fifo = folder.path() + "session.fifo";
  REQUIRE(::mkfifo(fifo.c_str(), 0600) == 0);
  std::thread writer([&] {
    const int fd = ::open(fifo.c_str(), O_WRONLY | O_CLOEXEC);
    if (fd < 0) return;
    const char* p = kSession.data();
    size_t left = kSession.size();
    while (left > 0) {
      const ssize_t n = ::write(fd, p, left);
      if (n <= 0) break;
      p += n;
      left -= static_cast<size_t>(n);
    }
    ::close(fd);
  });
  Result<Session> s = LoadSession(fifo);
  writer.join();
  REQUIRE(s.ok());
  CHECK(s.value().path == fifo);
  CHECK(s.value().sha256 == Sha256Hex(kSession));
  REQUIRE(s.value().tags.size() == 2);
  CHECK(s.value().tags[1].size() == 2);
}

}  // namespace
}  // namespace metro::internal
