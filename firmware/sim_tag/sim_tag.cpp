// metro_sim_tag: the tag's push receiver and power-fail-safe update (firmware/src, the C code
// the tag runs) on a RAM flash, talking on a pseudo-terminal as the BLE central's serial port
// would, so `calibrate push --port <pty>` is tested end to end over a real tty.
//
//   metro_sim_tag [--device-id HEX16] [--flash FILE] [--drop-frame K] [--dup-frame K]
//                 [--corrupt-frame K] [--drop-response K] [--hangup-after N]
//                 [--flash-write-error N] [--lie readback|execute-seq|get-crc|info-crc]
//
// Prints "pty: /dev/pts/N" on stdout once the terminal (raw, 230400 baud) is ready, then
// serves until SIGTERM/SIGINT or the hang-up fault. Frame numbers count the SLIP frames
// received from the PC (1-based); every fault option may be repeated.
//   --drop-frame K        frame K is lost (never reaches the receiver)
//   --dup-frame K         frame K arrives twice
//   --corrupt-frame K     one byte of frame K is changed (the receiver answers NAK)
//   --drop-response K     the tag's K-th answer is lost on the way back
//   --hangup-after N      after answering frame N the tag closes the link and exits
//   --flash-write-error N the N-th flash write fails (CAL_EXECUTE answers FLASH_ERROR)
//   --lie WHAT            the tag lies in its answers (the receiver's own state is honest):
//                         readback: CAL_READ's first data byte is changed; execute-seq:
//                         CAL_EXECUTE's SUCCESS names seq + 1; get-crc: CAL_GET_CRC's CRC-32
//                         is changed; info-crc: GET_INFO's active CRC-32 is changed
//   --flash FILE          the two 1024-byte slot pages (A then B): loaded when the file exists,
//                         saved after each committed update and at exit.
// Exit status: 0 after a signal or the hang-up (and --help), 2 for bad arguments, 1 for a
// system error. The options are parsed by CLI11; --help lists them with their defaults.
#include <fcntl.h>
#include <poll.h>
#include <pty.h>
#include <termios.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <set>
#include <string>
#include <vector>

extern "C" {
#include "metro_fw/blob.h"
#include "metro_fw/push.h"
}

namespace {

volatile std::sig_atomic_t g_stop = 0;
void OnSignal(int) { g_stop = 1; }

struct Options {
  uint32_t device_id[2] = {0x12345678u, 0x9ABCDEF0u};
  std::string flash_file;
  std::set<long> drop_frames, dup_frames, corrupt_frames, drop_responses;
  long hangup_after = -1;
  long flash_write_error = -1;
  std::set<std::string> lies;  // --lie
};

struct Sim {
  Options opt;
  std::vector<uint8_t> mem = std::vector<uint8_t>(2 * METRO_FW_PAGE_SIZE, 0xFF);
  long writes = 0;
  long responses = 0;
  int master = -1;
};

bool InRange(uint32_t addr, uint32_t len) {
  return addr >= METRO_FW_SLOT_A_ADDR &&
         addr - METRO_FW_SLOT_A_ADDR + len <= 2 * METRO_FW_PAGE_SIZE;
}

int FlashRead(void* ctx, uint32_t addr, uint8_t* dst, uint32_t len) {
  auto* s = static_cast<Sim*>(ctx);
  if (!InRange(addr, len)) return -1;
  std::memcpy(dst, s->mem.data() + (addr - METRO_FW_SLOT_A_ADDR), len);
  return 0;
}

int FlashErase(void* ctx, uint32_t addr) {
  auto* s = static_cast<Sim*>(ctx);
  if (addr % METRO_FW_PAGE_SIZE != 0 || !InRange(addr, METRO_FW_PAGE_SIZE)) return -1;
  std::memset(s->mem.data() + (addr - METRO_FW_SLOT_A_ADDR), 0xFF, METRO_FW_PAGE_SIZE);
  return 0;
}

int FlashWrite(void* ctx, uint32_t addr, const uint8_t* src, uint32_t len) {
  auto* s = static_cast<Sim*>(ctx);
  if (++s->writes == s->opt.flash_write_error) return -1;
  if (addr % 4 != 0 || len % 4 != 0 || !InRange(addr, len)) return -1;
  for (uint32_t i = 0; i < len; ++i) s->mem[addr - METRO_FW_SLOT_A_ADDR + i] &= src[i];
  return 0;
}

// The answer `data` (one SLIP-encoded frame, as metro_fw_push sends it) with the --lie faults
// applied, encoded again with a valid CRC-16: a tag that lies, not a link that corrupts.
std::vector<uint8_t> Lie(const Options& o, const uint8_t* data, uint32_t len) {
  std::vector<uint8_t> frame;
  for (uint32_t i = 0; i < len; ++i) {
    if (data[i] == METRO_FW_SLIP_END) continue;
    if (data[i] == METRO_FW_SLIP_ESC && i + 1 < len) {
      frame.push_back(data[++i] == METRO_FW_SLIP_ESC_END ? METRO_FW_SLIP_END : METRO_FW_SLIP_ESC);
    } else {
      frame.push_back(data[i]);
    }
  }
  const int n = metro_fw_frame_parse(frame.data(), static_cast<uint32_t>(frame.size()));
  if (n < 1 || o.lies.empty()) return std::vector<uint8_t>(data, data + len);
  const uint8_t op = frame[0] & static_cast<uint8_t>(~METRO_FW_PUSH_RESPONSE_BIT);
  std::vector<uint8_t> p(frame.begin() + 4, frame.begin() + 4 + n);  // result, then the rest
  const bool success = p[0] == METRO_FW_RES_SUCCESS;
  if (success && op == METRO_FW_OP_CAL_READ && o.lies.count("readback") && p.size() > 1) {
    p[1] ^= 0x01;
  } else if (success && op == METRO_FW_OP_CAL_EXECUTE && o.lies.count("execute-seq") &&
             p.size() >= 6) {
    ++p[2];  // seq u32 at 2..5, little-endian (seq + 1 unless its low byte is 0xFF)
  } else if (success && op == METRO_FW_OP_CAL_GET_CRC && o.lies.count("get-crc") && p.size() >= 7) {
    p[3] ^= 0x01;  // crc32 at 3..6
  } else if (success && op == METRO_FW_OP_GET_INFO && o.lies.count("info-crc") && p.size() >= 22 &&
             p[3] != 0xFF) {
    p[18] ^= 0x01;  // active_crc32 at 18..21, with an active slot
  }
  std::vector<uint8_t> out(2 * METRO_FW_PUSH_MAX_FRAME + 2);
  uint32_t out_len = 0;
  if (metro_fw_frame_encode(frame[0], frame[1], p.data(), static_cast<uint32_t>(p.size()),
                            out.data(), static_cast<uint32_t>(out.size()),
                            &out_len) != METRO_FW_OK) {
    return std::vector<uint8_t>(data, data + len);
  }
  out.resize(out_len);
  return out;
}

int Send(void* ctx, const uint8_t* in, uint32_t in_len) {
  auto* s = static_cast<Sim*>(ctx);
  if (s->opt.drop_responses.count(++s->responses) != 0) return 0;
  const std::vector<uint8_t> answer = Lie(s->opt, in, in_len);
  const uint8_t* data = answer.data();
  const uint32_t len = static_cast<uint32_t>(answer.size());
  uint32_t done = 0;
  while (done < len) {
    const ssize_t n = ::write(s->master, data + done, len - done);
    if (n < 0) {
      if (errno == EINTR || errno == EAGAIN) continue;
      return -1;
    }
    done += static_cast<uint32_t>(n);
  }
  return 0;
}

bool SaveFlash(const Sim& s) {
  if (s.opt.flash_file.empty()) return true;
  const std::string tmp = s.opt.flash_file + ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(s.mem.data()),
              static_cast<std::streamsize>(s.mem.size()));
    if (!out.good()) return false;
  }
  return std::rename(tmp.c_str(), s.opt.flash_file.c_str()) == 0;
}

int Usage(const char* why) {
  std::fprintf(stderr, "metro_sim_tag: %s\n", why);
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  Sim sim;
  Options& o = sim.opt;
  CLI::App app{
      "metro_sim_tag: the tag's push receiver and power-fail-safe update (firmware/src) on a "
      "RAM flash, on a pseudo-terminal (raw, 230400 baud) as the BLE central's serial port. "
      "Prints \"pty: /dev/pts/N\" once ready and serves until SIGTERM/SIGINT or the hang-up "
      "fault. Frames count the SLIP frames received from the PC (1-based); the fault options "
      "may be repeated. Exit status: 0 after a signal or the hang-up, 2 for bad arguments, 1 "
      "for a system error."};
  std::string device_id = "9ABCDEF012345678";
  std::vector<long> drop, dup, corrupt, drop_response;
  app.add_option("--device-id", device_id,
                 "the tag's FICR device ID as 16 hex digits (DEVICEID[1] then DEVICEID[0])")
      ->capture_default_str();
  app.add_option("--flash", o.flash_file,
                 "the two 1024-byte slot pages (A then B): loaded when the file exists, saved "
                 "after each committed update and at exit (default: RAM only)");
  app.add_option("--drop-frame", drop, "frame K is lost (never reaches the receiver)")
      ->check(CLI::PositiveNumber);
  app.add_option("--dup-frame", dup, "frame K arrives twice")->check(CLI::PositiveNumber);
  app.add_option("--corrupt-frame", corrupt,
                 "one byte of frame K is changed (the receiver answers NAK)")
      ->check(CLI::PositiveNumber);
  app.add_option("--drop-response", drop_response, "the tag's K-th answer is lost on the way back")
      ->check(CLI::PositiveNumber);
  app.add_option("--hangup-after", o.hangup_after,
                 "after answering frame N the tag closes the link and exits (default: never)")
      ->check(CLI::PositiveNumber);
  app.add_option("--flash-write-error", o.flash_write_error,
                 "the N-th flash write fails: CAL_EXECUTE answers FLASH_ERROR (default: never)")
      ->check(CLI::PositiveNumber);
  std::vector<std::string> lies;
  app.add_option("--lie", lies,
                 "the tag lies in its answers: readback (CAL_READ's first data byte changed), "
                 "execute-seq (CAL_EXECUTE's SUCCESS names seq + 1), get-crc (CAL_GET_CRC's "
                 "CRC-32 changed), info-crc (GET_INFO's active CRC-32 changed)")
      ->check(CLI::IsMember({"readback", "execute-seq", "get-crc", "info-crc"}));
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  if (device_id.size() != 16 || std::strspn(device_id.c_str(), "0123456789abcdefABCDEF") != 16) {
    return Usage("--device-id takes 16 hex digits");
  }
  const unsigned long long id = std::strtoull(device_id.c_str(), nullptr, 16);
  o.device_id[0] = static_cast<uint32_t>(id & 0xFFFFFFFFu);
  o.device_id[1] = static_cast<uint32_t>(id >> 32);
  o.drop_frames.insert(drop.begin(), drop.end());
  o.dup_frames.insert(dup.begin(), dup.end());
  o.corrupt_frames.insert(corrupt.begin(), corrupt.end());
  o.drop_responses.insert(drop_response.begin(), drop_response.end());
  o.lies.insert(lies.begin(), lies.end());
  if (!o.flash_file.empty()) {
    std::ifstream in(o.flash_file, std::ios::binary);
    if (in.good()) {
      std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(in)), {});
      if (bytes.size() != sim.mem.size()) return Usage("--flash file is not 2048 bytes");
      sim.mem = bytes;
    }
  }

  int slave = -1;
  termios tio{};
  ::cfmakeraw(&tio);
  tio.c_cflag |= CLOCAL | CREAD;
  ::cfsetispeed(&tio, B230400);
  ::cfsetospeed(&tio, B230400);
  if (::openpty(&sim.master, &slave, nullptr, &tio, nullptr) != 0) {
    std::perror("metro_sim_tag: openpty");
    return 1;
  }
  // Holding the slave open keeps the master readable when the PC closes its end.
  std::signal(SIGTERM, OnSignal);
  std::signal(SIGINT, OnSignal);
  std::signal(SIGPIPE, SIG_IGN);

  metro_fw_flash flash{};
  flash.read = FlashRead;
  flash.erase_page = FlashErase;
  flash.write = FlashWrite;
  flash.ctx = &sim;
  flash.slot_addr[0] = METRO_FW_SLOT_A_ADDR;
  flash.slot_addr[1] = METRO_FW_SLOT_B_ADDR;
  static metro_fw_push push;  // 1.2 KiB, as on the tag: static storage
  if (metro_fw_push_init(&push, &flash, o.device_id, Send, &sim) != METRO_FW_OK) return 1;

  std::printf("pty: %s\n", ::ttyname(slave));
  std::fflush(stdout);

  std::vector<uint8_t> frame;
  long frames = 0;
  bool hangup = false;
  while (!g_stop && !hangup) {
    pollfd p{sim.master, POLLIN, 0};
    const int r = ::poll(&p, 1, 100);
    if (r <= 0 || (p.revents & POLLIN) == 0) continue;
    uint8_t buf[256];
    const ssize_t n = ::read(sim.master, buf, sizeof buf);
    if (n <= 0) continue;
    for (ssize_t i = 0; i < n && !hangup; ++i) {
      if (buf[i] != METRO_FW_SLIP_END) {
        frame.push_back(buf[i]);
        continue;
      }
      if (frame.empty()) continue;
      ++frames;
      std::vector<uint8_t> wire;
      wire.push_back(METRO_FW_SLIP_END);
      wire.insert(wire.end(), frame.begin(), frame.end());
      wire.push_back(METRO_FW_SLIP_END);
      frame.clear();
      if (o.corrupt_frames.count(frames) != 0) {
        uint8_t& b = wire[wire.size() / 2];
        uint8_t c = static_cast<uint8_t>(b ^ 0x55);
        if (c == METRO_FW_SLIP_END || c == METRO_FW_SLIP_ESC) c = static_cast<uint8_t>(b ^ 0x11);
        b = c;
      }
      const int copies = o.drop_frames.count(frames) != 0  ? 0
                         : o.dup_frames.count(frames) != 0 ? 2
                                                           : 1;
      for (int k = 0; k < copies; ++k) {
        (void)metro_fw_push_rx(&push, wire.data(), static_cast<uint32_t>(wire.size()));
      }
      if (push.updated) {
        push.updated = 0;
        if (!SaveFlash(sim))
          std::fprintf(stderr, "metro_sim_tag: cannot save %s\n", o.flash_file.c_str());
      }
      if (frames == o.hangup_after) hangup = true;
    }
  }
  ::close(sim.master);
  ::close(slave);
  return SaveFlash(sim) ? 0 : 1;
}
