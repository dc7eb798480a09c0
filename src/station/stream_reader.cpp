#include "metro/station/stream_reader.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <poll.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <thread>

#include "metro/serial/serial_port.hpp"

namespace metro::station {

namespace {
using Clock = std::chrono::steady_clock;
double Since(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}
}  // namespace

bool StreamReaderOptions::IsValid(std::string* why) const {
  if (!(idle_timeout_s > 0) || !(reconnect_s >= 0)) {
    if (why != nullptr) *why = "--idle-timeout-s must be > 0 and --reconnect-s >= 0";
    return false;
  }
  return true;
}

struct RawStreamReader::Impl {
  std::string path;
  StreamReaderOptions o;
  bool port = false;
  std::unique_ptr<serial::SerialPort> serial;
  int fd = -1;  // A followed file or FIFO.
  std::string buffer;
  int64_t lines = 0;
  bool lost = false;
  bool drop_partial = false;
  Clock::time_point last_byte = Clock::now();
  Clock::time_point lost_at = Clock::now();
  Clock::time_point last_try = Clock::now();

  ~Impl() {
    if (fd >= 0) ::close(fd);
  }

  Status OpenPort() {
    Result<std::unique_ptr<serial::SerialPort>> p = serial::SerialPort::Open(path, o.baud);
    if (!p.ok()) return p.error();
    serial = std::move(p).value();
    return Status();
  }

  // Bytes into the buffer; false with `why` when the source is lost.
  bool Fill(int timeout_ms, std::string* why) {
    uint8_t chunk[4096];
    if (port) {
      Result<size_t> n = serial->Read(chunk, sizeof chunk, timeout_ms);
      if (!n.ok()) {
        *why = n.error().ToString();
        return false;
      }
      buffer.append(reinterpret_cast<const char*>(chunk), n.value());
      if (n.value() > 0) last_byte = Clock::now();
      return true;
    }
    pollfd p{fd, POLLIN, 0};
    ssize_t n = ::read(fd, chunk, sizeof chunk);
    if (n == 0 || (n < 0 && errno == EAGAIN)) {
      // End of what was written so far (tail -f): wait, then look again.
      if (::poll(&p, 1, 0) <= 0 || n == 0) {
        std::this_thread::sleep_for(std::chrono::milliseconds(std::min(timeout_ms, 50)));
      }
      n = ::read(fd, chunk, sizeof chunk);
    }
    if (n > 0) {
      buffer.append(reinterpret_cast<const char*>(chunk), static_cast<size_t>(n));
      last_byte = Clock::now();
    }
    return true;
  }
};

RawStreamReader::RawStreamReader(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
RawStreamReader::~RawStreamReader() = default;
bool RawStreamReader::IsPort() const { return impl_->port; }

Result<std::unique_ptr<RawStreamReader>> RawStreamReader::Open(const std::string& path,
                                                               const StreamReaderOptions& o) {
  auto impl = std::make_unique<Impl>();
  impl->path = path;
  impl->o = o;
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) {
    return MakeError(path, 0, fmt::format("cannot open: {}", std::strerror(errno)));
  }
  if (S_ISDIR(st.st_mode)) return MakeError(path, 0, "is a directory, not a port or a file");
  impl->port = S_ISCHR(st.st_mode);
  if (impl->port) {
    if (Status s = impl->OpenPort(); !s.ok()) return s.error();
    impl->drop_partial = true;
  } else {
    impl->fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
    if (impl->fd < 0) {
      return MakeError(path, 0, fmt::format("cannot open: {}", std::strerror(errno)));
    }
  }
  return std::unique_ptr<RawStreamReader>(new RawStreamReader(std::move(impl)));
}

RawStreamReader::Item RawStreamReader::Next(int timeout_ms) {
  Impl& m = *impl_;
  Item item;
  if (m.lost) {
    if (Since(m.lost_at) > m.o.reconnect_s) {
      item.kind = Kind::kEnded;
      item.why = fmt::format("{} did not come back within {:g} s", m.path, m.o.reconnect_s);
      return item;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(std::min(timeout_ms, 100)));
    if (!m.OpenPort().ok()) return item;
    m.lost = false;
    m.drop_partial = true;
    m.buffer.clear();
    m.last_byte = Clock::now();
    item.kind = Kind::kResumed;
    item.why = fmt::format("{} is back", m.path);
    return item;
  }
  for (;;) {
    const size_t nl = m.buffer.find('\n');
    if (nl != std::string::npos) {
      std::string line = m.buffer.substr(0, nl);
      m.buffer.erase(0, nl + 1);
      if (m.drop_partial) {
        m.drop_partial = false;
        continue;
      }
      if (!line.empty() && line.back() == '\r') line.pop_back();
      item.kind = Kind::kLine;
      item.line = std::move(line);
      item.line_number = ++m.lines;
      return item;
    }
    if (Since(m.last_byte) > m.o.idle_timeout_s) {
      item.kind = Kind::kEnded;
      item.why = fmt::format("no data from {} for {:g} s", m.path, m.o.idle_timeout_s);
      return item;
    }
    const size_t before = m.buffer.size();
    std::string why;
    if (!m.Fill(timeout_ms, &why)) {
      m.serial.reset();
      m.lost = true;
      m.lost_at = Clock::now();
      item.kind = Kind::kLost;
      item.why = why;
      return item;
    }
    if (m.buffer.size() == before) return item;  // kNothing
  }
}

}  // namespace metro::station
