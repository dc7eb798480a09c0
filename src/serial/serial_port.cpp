#include "metro/serial/serial_port.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <poll.h>
#include <sys/file.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>

namespace metro::serial {
namespace {

bool BaudConstant(int baud, speed_t* out) {
  switch (baud) {
    case 9600:
      *out = B9600;
      return true;
    case 19200:
      *out = B19200;
      return true;
    case 38400:
      *out = B38400;
      return true;
    case 57600:
      *out = B57600;
      return true;
    case 115200:
      *out = B115200;
      return true;
    case 230400:
      *out = B230400;
      return true;
    case 460800:
      *out = B460800;
      return true;
    case 921600:
      *out = B921600;
      return true;
    default:
      return false;
  }
}

}  // namespace

Result<std::unique_ptr<SerialPort>> SerialPort::Open(const std::string& path, int baud) {
  speed_t speed;
  if (!BaudConstant(baud, &speed))
    return MakeError(path, 0, fmt::format("unsupported baud rate {}", baud));
  const int fd = ::open(path.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) return MakeError(path, 0, fmt::format("cannot open: {}", std::strerror(errno)));
  auto fail = [&](const char* what) {
    const int e = errno;
    ::close(fd);
    return MakeError(path, 0, fmt::format("{}: {}", what, std::strerror(e)));
  };
  if (::flock(fd, LOCK_EX | LOCK_NB) != 0) return fail("in use by another program (flock)");
  termios tio{};
  if (::tcgetattr(fd, &tio) != 0) return fail("not a serial port (tcgetattr)");
  ::cfmakeraw(&tio);  // no echo, no line editing, no CR/LF translation, 8 bits
  tio.c_cflag &= ~static_cast<tcflag_t>(PARENB | CSTOPB | CSIZE | CRTSCTS);
  tio.c_cflag |= CS8 | CLOCAL | CREAD;
  tio.c_iflag &= ~static_cast<tcflag_t>(IXON | IXOFF | IXANY);
  tio.c_cc[VMIN] = 0;
  tio.c_cc[VTIME] = 0;
  if (::cfsetispeed(&tio, speed) != 0 || ::cfsetospeed(&tio, speed) != 0) return fail("cfsetspeed");
  if (::tcsetattr(fd, TCSANOW, &tio) != 0) return fail("tcsetattr");
  ::tcflush(fd, TCIOFLUSH);
  return std::unique_ptr<SerialPort>(new SerialPort(fd, path));
}

SerialPort::~SerialPort() { ::close(fd_); }

Status SerialPort::Write(const uint8_t* data, size_t size) {
  size_t done = 0;
  while (done < size) {
    const ssize_t n = ::write(fd_, data + done, size - done);
    if (n > 0) {
      done += static_cast<size_t>(n);
      continue;
    }
    if (n < 0 && errno == EINTR) continue;
    if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) {
      pollfd p{fd_, POLLOUT, 0};
      if (::poll(&p, 1, 1000) <= 0 || (p.revents & (POLLHUP | POLLERR)) != 0) {
        return MakeError(path_, 0, "write: the link does not drain (hung up?)");
      }
      continue;
    }
    // A serial device (or pty) whose other end went away fails writes with EIO, as Read
    // sees it: the same words either way, whichever call meets the hang-up first.
    if (errno == EIO) return MakeError(path_, 0, "write: the link hung up");
    return MakeError(path_, 0, fmt::format("write: {}", std::strerror(errno)));
  }
  return Status::Ok();
}

Result<size_t> SerialPort::Read(uint8_t* data, size_t capacity, int timeout_ms) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms);
  for (;;) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
        deadline - std::chrono::steady_clock::now());
    pollfd p{fd_, POLLIN, 0};
    const int r = ::poll(&p, 1, static_cast<int>(std::max<int64_t>(0, left.count())));
    if (r < 0 && errno == EINTR) continue;
    if (r < 0) return MakeError(path_, 0, fmt::format("poll: {}", std::strerror(errno)));
    if (r == 0) return size_t{0};
    if ((p.revents & POLLIN) != 0) {
      const ssize_t n = ::read(fd_, data, capacity);
      if (n > 0) return static_cast<size_t>(n);
      if (n < 0 && (errno == EAGAIN || errno == EINTR)) continue;
      if (n == 0 || errno == EIO) return MakeError(path_, 0, "the link hung up");
      return MakeError(path_, 0, fmt::format("read: {}", std::strerror(errno)));
    }
    if ((p.revents & (POLLHUP | POLLERR | POLLNVAL)) != 0) {
      return MakeError(path_, 0, "the link hung up");
    }
  }
}

}  // namespace metro::serial
