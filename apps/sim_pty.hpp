// The simulators' pseudo-terminal (metro_sim_receiver, metro_sim_raw_tag): a pty behind a
// symbolic link PATH that a program opens as its serial port, the monotonic clock and the stop
// flag their signal handlers set.
#pragma once

#include <fcntl.h>
#include <poll.h>
#include <pty.h>
#include <sys/ioctl.h>
#include <termios.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <string>
#include <string_view>

namespace metro::apps::sim {

// Set by the program's SIGINT/SIGTERM handler; every wait below returns when it is set.
inline volatile std::sig_atomic_t g_stop = 0;
// The program's name in messages.
inline const char* g_program = "metro_sim";

inline void OnSignal(int) { g_stop = 1; }

// SIGTERM and SIGINT set g_stop. Without SA_RESTART (std::signal sets it): a write blocked on
// a full pseudo-terminal, whose reader has gone, returns EINTR on SIGTERM and the loop sees
// g_stop; with it the write restarted and the program never ended (a README example hung its
// ctest for 600 s). SIGPIPE is ignored.
inline void InstallSignals() {
  struct sigaction stop {};
  stop.sa_handler = OnSignal;
  sigemptyset(&stop.sa_mask);
  stop.sa_flags = 0;
  sigaction(SIGTERM, &stop, nullptr);
  sigaction(SIGINT, &stop, nullptr);
  std::signal(SIGPIPE, SIG_IGN);
}

double Now() {
  timespec ts{};
  ::clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

void SleepUntil(double t) {
  timespec ts{};
  ts.tv_sec = static_cast<time_t>(std::floor(t));
  ts.tv_nsec = std::min(999999999L, static_cast<long>((t - std::floor(t)) * 1e9));
  // EINTR (a signal) returns early; the caller checks g_stop.
  ::clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr);
}

// The pty behind PATH. Packet mode on the master tells when the other side flushes its
// input, i.e. when a program opened the port (SerialPort::Open ends with tcflush).
class Pty {
 public:
  ~Pty() { Close(); }
  bool Open(const std::string& link) {
    termios tio{};
    ::cfmakeraw(&tio);
    tio.c_cflag |= CLOCAL | CREAD;
    ::cfsetispeed(&tio, B230400);
    ::cfsetospeed(&tio, B230400);
    if (::openpty(&master_, &slave_, nullptr, &tio, nullptr) != 0) {
      std::fprintf(stderr, "%s: openpty: %s\n", g_program, std::strerror(errno));
      return false;
    }
    int on = 1;
    if (::ioctl(master_, TIOCPKT, &on) != 0) {
      std::fprintf(stderr, "%s: TIOCPKT: %s\n", g_program, std::strerror(errno));
      return false;
    }
    link_ = link;
    const std::string tmp = link + ".tmp";
    ::unlink(tmp.c_str());
    if (::symlink(::ttyname(slave_), tmp.c_str()) != 0 ||
        ::rename(tmp.c_str(), link.c_str()) != 0) {
      std::fprintf(stderr, "%s: cannot make the link %s: %s\n", g_program, link.c_str(),
                   std::strerror(errno));
      return false;
    }
    return true;
  }
  std::string SlaveName() const { return ::ttyname(slave_); }
  // Waits until a program flushed the port's input (opened it); false when stopped.
  bool WaitForReader() {
    while (!g_stop) {
      pollfd p{master_, POLLIN | POLLPRI, 0};
      if (::poll(&p, 1, 100) <= 0) continue;
      unsigned char buf[512];
      const ssize_t n = ::read(master_, buf, sizeof buf);
      if (n >= 1 && buf[0] != TIOCPKT_DATA &&
          (buf[0] & (TIOCPKT_FLUSHREAD | TIOCPKT_FLUSHWRITE)) != 0) {
        return true;
      }
    }
    return false;
  }
  // Discards what the reader sent (a capture sends nothing) and control bytes.
  void Drain() {
    unsigned char buf[512];
    pollfd p{master_, POLLIN | POLLPRI, 0};
    while (::poll(&p, 1, 0) > 0 && (p.revents & (POLLIN | POLLPRI)) != 0) {
      if (::read(master_, buf, sizeof buf) <= 0) break;
    }
  }
  bool Write(std::string_view text) {
    size_t done = 0;
    while (done < text.size()) {
      // A signal after part of the text was written returns that count, not EINTR: look at
      // g_stop before blocking again.
      if (g_stop) return false;
      const ssize_t n = ::write(master_, text.data() + done, text.size() - done);
      if (n > 0) {
        done += static_cast<size_t>(n);
      } else if (n < 0 && (errno == EINTR || errno == EAGAIN)) {
        if (g_stop) return false;
        pollfd p{master_, POLLOUT, 0};
        ::poll(&p, 1, 100);
      } else {
        return false;
      }
    }
    return true;
  }
  // Waits (at most timeout_s) until the reader has taken every byte written: the slave's
  // input queue stays empty for 50 ms.
  void WaitUntilRead(double timeout_s) {
    const double until = Now() + timeout_s;
    int quiet = 0;
    while (!g_stop && Now() < until && quiet < 5) {
      int queued = 0;
      if (::ioctl(slave_, TIOCINQ, &queued) != 0) return;
      quiet = queued == 0 ? quiet + 1 : 0;
      ::poll(nullptr, 0, 10);
    }
  }
  // The cable is pulled: the link disappears, the reader sees a hang-up.
  void Close() {
    if (!link_.empty()) ::unlink(link_.c_str());
    link_.clear();
    if (master_ >= 0) ::close(master_);
    if (slave_ >= 0) ::close(slave_);
    master_ = slave_ = -1;
  }

 private:
  int master_ = -1;
  int slave_ = -1;
  std::string link_;
};

}  // namespace metro::apps::sim
