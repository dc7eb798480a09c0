#include "metro/io/session.hpp"

#include <fast_float/fast_float.h>
#include <fcntl.h>
#include <fmt/format.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <iterator>
#include <limits>
#include <new>
#include <queue>
#include <thread>

#include "core/parallel.hpp"
#include "io/csv_plan.hpp"
#include "io/session_internal.hpp"
#include "io/stdin_input.hpp"
#include "metro/core/angles.hpp"
#include "metro/core/file.hpp"
#include "metro/io/columns.hpp"
#include "metro/io/dataflash.hpp"
#include "metro/io/receiver.hpp"
#include "metro/io/ros_log.hpp"
#include "metro/io/session_io.hpp"
#include "metro/io/ulog.hpp"

namespace metro {

namespace {

struct FormatName {
  SessionFormat format;
  const char* name;
};
constexpr FormatName kFormatNames[] = {
    {SessionFormat::kAuto, "auto"},         {SessionFormat::kCsv, "csv"},
    {SessionFormat::kReceiver, "receiver"}, {SessionFormat::kImuTk, "imutk"},
    {SessionFormat::kEuroc, "euroc"},       {SessionFormat::kRaw, "raw"},
    {SessionFormat::kPhyphox, "phyphox"},   {SessionFormat::kSensorLogger, "sensorlogger"},
    {SessionFormat::kPhone, "phone"},       {SessionFormat::kULog, "ulog"},
    {SessionFormat::kMcap, "mcap"},         {SessionFormat::kRosbag1, "rosbag1"},
    {SessionFormat::kRosbag2, "rosbag2"},   {SessionFormat::kDataFlash, "dataflash"},
};

}  // namespace

bool IsBinaryLogFormat(SessionFormat format) {
  return format == SessionFormat::kULog || format == SessionFormat::kMcap ||
         format == SessionFormat::kRosbag1 || format == SessionFormat::kRosbag2 ||
         format == SessionFormat::kDataFlash;
}

const char* SessionFormatName(SessionFormat format) {
  for (const FormatName& f : kFormatNames) {
    if (f.format == format) return f.name;
  }
  return "?";
}

bool ParseSessionFormat(std::string_view name, SessionFormat* format) {
  for (const FormatName& f : kFormatNames) {
    if (name == f.name) {
      *format = f.format;
      return true;
    }
  }
  return false;
}

Result<ColumnMapping> ParseColumnMapping(std::string_view spec) {
  const size_t eq = spec.rfind('=');
  if (eq == std::string_view::npos || eq == 0) {
    return MakeError(
        fmt::format("--column '{}': expected SRC=DST, e.g. 'gyro_x (deg/s)=gx_dps' "
                    "(or SRC= to leave the column out)",
                    spec));
  }
  ColumnMapping m{std::string(spec.substr(0, eq)), std::string(spec.substr(eq + 1))};
  if (!m.canonical.empty() && !IsValidColumnName(m.canonical)) {
    return MakeError(
        fmt::format("--column '{}': '{}' is not a canonical column name "
                    "([a-z][a-z0-9_]* with its unit, e.g. gx_dps; docs/formats.md)",
                    spec, m.canonical));
  }
  return m;
}

Result<std::vector<ColumnMapping>> LoadColumnMappings(const std::string& path) {
  auto text = ReadFile(path);
  if (!text.ok()) return text.error();
  std::vector<ColumnMapping> out;
  size_t pos = 0;
  int64_t line = 0;
  const std::string& t = text.value();
  while (pos < t.size()) {
    size_t nl = t.find('\n', pos);
    if (nl == std::string::npos) nl = t.size();
    std::string_view l(t.data() + pos, nl - pos);
    pos = nl + 1;
    ++line;
    if (!l.empty() && l.back() == '\r') l.remove_suffix(1);
    while (!l.empty() && (l.front() == ' ' || l.front() == '\t')) l.remove_prefix(1);
    if (l.empty() || l.front() == '#') continue;
    auto m = ParseColumnMapping(l);
    if (!m.ok()) {
      return MakeError(path, line, 1,
                       fmt::format("expected one SRC=DST mapping per line: {}", m.error().message));
    }
    out.push_back(std::move(m).value());
  }
  return out;
}

const Quantity* Tag::Find(std::string_view name) const {
  for (const Quantity& q : quantities) {
    if (q.name == name) return &q;
  }
  return nullptr;
}

void Tag::KeepRows(size_t begin, size_t end) {
  end = std::min(end, size());
  begin = std::min(begin, end);
  const auto keep = [begin, end](auto& v) {
    if (v.empty()) return;  // A column without values (none in the file).
    v.erase(v.begin() + static_cast<std::ptrdiff_t>(end), v.end());
    v.erase(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(begin));
  };
  keep(t_s);
  keep(t_ns);
  keep(line);
  for (Quantity& q : quantities) keep(q.values);
  for (TextColumn& c : text_columns) keep(c.values);
}

Quantity* Tag::Find(std::string_view name) {
  for (Quantity& q : quantities) {
    if (q.name == name) return &q;
  }
  return nullptr;
}

const Tag* Session::FindTag(int sensor) const {
  for (const Tag& t : tags) {
    if (t.sensor == sensor) return &t;
  }
  return nullptr;
}

Session::~Session() {
  // Below this the pages go as fast on one core as the threads would take to start.
  constexpr size_t kParallelReleaseBytes = size_t{64} << 20;
  size_t bytes = 0;
  for (const Tag& tag : tags) {
    bytes += tag.t_s.capacity() * sizeof(double) + tag.t_ns.capacity() * sizeof(int64_t) +
             tag.line.capacity() * sizeof(uint32_t);
    for (const Quantity& q : tag.quantities) bytes += q.values.capacity() * sizeof(double);
  }
  if (bytes >= kParallelReleaseBytes) internal::ReturnColumnPages(this, 0);
}

bool LoadOptions::IsValid(std::string* why) const {
  // The central's DELTAT is a 16-bit count of its 32768 Hz clock (at most 2 s); a minute
  // allows any other receiver and keeps the times of 2^32 frames far from overflow.
  constexpr double kMaxFramePeriodS = 60.0;
  if (!(frame_period_s > 0.0 && frame_period_s <= kMaxFramePeriodS)) {
    if (why) {
      *why = fmt::format("frame_period_s must be in (0, {:g}] s, got {:g}", kMaxFramePeriodS,
                         frame_period_s);
    }
    return false;
  }
  if (threads < 0) {
    if (why) *why = "threads must be >= 0 (0 = all cores)";
    return false;
  }
  return true;
}

namespace internal {

Result<Session> NamedAsStream(Result<Session> session, const std::string& copy_path,
                              const std::string& display_name) {
  if (session.ok()) {
    session.value().path = display_name;
    return session;
  }
  Error error = session.error();
  if (error.file == copy_path) error.file = display_name;
  return error;
}

Error TooManyLinesError(const std::string& path, int64_t line) {
  return MakeError(path, line,
                   fmt::format("more than {} lines: metro keeps each observation's source line "
                               "as a 32-bit number; split the file",
                               kMaxLineNumber));
}

Error OutOfMemoryError(const std::string& path) {
  return MakeError(path, 0,
                   "out of memory while loading: the session's columns (8 bytes per number) "
                   "do not fit in this machine's memory; split the file by time or by tag");
}

void ReturnColumnPages(Session* session, int threads) {
#if defined(__linux__) && defined(MADV_DONTNEED)
  // The whole pages inside each column; the allocator's bookkeeping just before and after
  // a column's values is never on one of them.
  std::vector<std::pair<uintptr_t, uintptr_t>> pages;
  auto add = [&pages](const auto& column) {
    constexpr uintptr_t kPage = 4096;
    const uintptr_t begin = reinterpret_cast<uintptr_t>(column.data());
    const uintptr_t lo = (begin + kPage - 1) & ~(kPage - 1);
    const uintptr_t hi = (begin + column.capacity() * sizeof(column[0])) & ~(kPage - 1);
    if (hi >= lo + (uintptr_t{1} << 20)) pages.emplace_back(lo, hi);
  };
  for (const Tag& tag : session->tags) {
    add(tag.t_s);
    add(tag.t_ns);
    add(tag.line);
    for (const Quantity& q : tag.quantities) add(q.values);
  }
  // munmap needs the address space's lock exclusively, so frees in several threads would
  // still run one after another; MADV_DONTNEED needs it only shared, so the threads return
  // the pages side by side.
  ParallelFor(pages.size(), threads, [&pages](size_t i) {
    ::madvise(reinterpret_cast<void*>(pages[i].first), pages[i].second - pages[i].first,
              MADV_DONTNEED);
  });
#else
  (void)session;
  (void)threads;
#endif
}

void AddTextOrUnknownColumn(const std::string& name, bool unknown, const std::string& unit,
                            std::vector<std::string> values, Tag* tag) {
  if (unknown) {
    std::vector<double> numbers(values.size());
    bool numeric = true;
    for (size_t i = 0; i < values.size() && numeric; ++i) {
      const std::string& s = values[i];
      const char* b = s.data();
      const char* e = s.data() + s.size();
      if (b < e && *b == '+') ++b;
      const auto r = fast_float::from_chars(b, e, numbers[i]);
      numeric = b < e && r.ec == std::errc() && r.ptr == e && std::isfinite(numbers[i]);
    }
    if (numeric) {
      Quantity q;
      q.name = name;
      q.unit = unit;
      q.origin = QuantityOrigin::kUnknown;
      q.values = std::move(numbers);
      tag->quantities.push_back(std::move(q));
      return;
    }
  }
  tag->text_columns.push_back(TextColumn{name, std::move(values)});
}

}  // namespace internal

std::string DeriveEulerIfAbsent(Tag* tag) {
  const Quantity* qw = tag->Find("qw");
  const Quantity* qx = tag->Find("qx");
  const Quantity* qy = tag->Find("qy");
  const Quantity* qz = tag->Find("qz");
  if (!qw || !qx || !qy || !qz) return "";
  if (tag->Find("yaw_deg") || tag->Find("pitch_deg") || tag->Find("roll_deg")) return "";
  const size_t n = tag->size();
  Quantity yaw{"yaw_deg", "deg", QuantityOrigin::kDerived, std::vector<double>(n)};
  Quantity pitch{"pitch_deg", "deg", QuantityOrigin::kDerived, std::vector<double>(n)};
  Quantity roll{"roll_deg", "deg", QuantityOrigin::kDerived, std::vector<double>(n)};
  // A rotation is a unit quaternion; norms far from 1 (raw fixed-point counts, a wrong
  // column) are reported, from the largest-component scaling that cannot overflow.
  constexpr double kNormTolerance = 0.01;
  double min_norm = std::numeric_limits<double>::infinity();
  double max_norm = 0.0;
  size_t off = 0;
  for (size_t i = 0; i < n; ++i) {
    const Quaternion q{qw->values[i], qx->values[i], qy->values[i], qz->values[i]};
    const EulerDeg e = EulerFromQuaternion(q);
    yaw.values[i] = e.yaw_deg;
    pitch.values[i] = e.pitch_deg;
    roll.values[i] = e.roll_deg;
    const double m = std::max({std::fabs(q.w), std::fabs(q.x), std::fabs(q.y), std::fabs(q.z)});
    const double norm =
        m > 0.0 ? m * std::hypot(std::hypot(q.w / m, q.x / m), std::hypot(q.y / m, q.z / m)) : 0.0;
    if (!std::isfinite(norm)) continue;  // A missing value: no angle, nothing to check.
    min_norm = std::min(min_norm, norm);
    max_norm = std::max(max_norm, norm);
    if (std::fabs(norm - 1.0) > kNormTolerance) ++off;
  }
  tag->quantities.push_back(std::move(yaw));
  tag->quantities.push_back(std::move(pitch));
  tag->quantities.push_back(std::move(roll));
  if (off == 0) return "";
  return fmt::format(
      "sensor {}: {} of {} quaternions have a norm more than {:g} from 1 (norms {:.6g} to "
      "{:.6g}): yaw_deg, pitch_deg and roll_deg are derived from their directions, but check "
      "the quaternions' scale (raw Q30 counts?)",
      tag->sensor, off, n, kNormTolerance, min_norm, max_norm);
}

namespace {

bool IsHexDigit(char c) {
  return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f') || (c >= 'A' && c <= 'F');
}

bool LooksLikeReceiverLine(std::string_view line) {
  if (line.size() != static_cast<size_t>(kReceiverLineHexChars)) return false;
  return std::all_of(line.begin(), line.end(), IsHexDigit);
}

}  // namespace

Result<SessionFormat> DetectSessionFormat(const std::string& path) {
  if (IsRosbag2Path(path)) return SessionFormat::kRosbag2;
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return MakeError(path, 0, std::string("cannot open: ") + std::strerror(errno));
  std::string head(1 << 16, '\0');
  ssize_t got = 0;
  for (;;) {
    got = ::read(fd, head.data(), head.size());
    if (got >= 0 || errno != EINTR) break;
  }
  ::close(fd);
  if (got < 0) return MakeError(path, 0, std::string("cannot read: ") + std::strerror(errno));
  head.resize(static_cast<size_t>(got));
  if (IsULogMagic(head)) return SessionFormat::kULog;
  if (IsMcapMagic(head)) return SessionFormat::kMcap;
  if (IsRosbag1Magic(head)) return SessionFormat::kRosbag1;
  if (IsDataFlashMagic(head)) return SessionFormat::kDataFlash;
  if (head.compare(0, 3, "\xEF\xBB\xBF") == 0) head.erase(0, 3);  // UTF-8 byte-order mark.
  if (head.empty()) {
    return MakeError(path, 0, "empty file: expected a session.csv or a receiver capture");
  }
  size_t control = 0;
  for (unsigned char c : head) {
    if (c == 0) {
      return MakeError(path, 0,
                       "binary data (NUL bytes): expected a text session.csv, a "
                       "receiver capture or a PX4 ULog (its first bytes \"ULog\" 01 12 35), an "
                       "MCAP (89 \"MCAP0\" 0d 0a), a ROS 1 bag (\"#ROSBAG V2.0\") or an ArduPilot "
                       "DataFlash log (a3 95 80 80 59 \"FMT\")");
    }
    if (c < 0x20 && c != '\n' && c != '\r' && c != '\t') ++control;
  }
  if (control * 20 > head.size()) {
    return MakeError(path, 0,
                     "binary data (control bytes): expected a text session.csv, a "
                     "receiver capture or a PX4 ULog (its first bytes \"ULog\" 01 12 35), an "
                     "MCAP (89 \"MCAP0\" 0d 0a), a ROS 1 bag (\"#ROSBAG V2.0\") or an ArduPilot "
                     "DataFlash log (a3 95 80 80 59 \"FMT\")");
  }
  // The first meaningful lines: a receiver capture when most of them are receiver lines
  // (a cut first line or a terminal program's banner does not defeat it).
  size_t meaningful = 0;
  size_t receiver = 0;
  size_t pos = 0;
  // Lines end at LF (CRLF included), or at CR in a file with no LF (classic Mac OS, some
  // loggers), as the CSV planner splits them.
  const char line_end =
      head.find('\n') == std::string::npos && head.find('\r') != std::string::npos ? '\r' : '\n';
  while (pos < head.size() && meaningful < 20) {
    size_t nl = head.find(line_end, pos);
    if (nl == std::string::npos) {
      if (pos > 0 && meaningful > 0) break;  // A line cut by the 64 kB head.
      nl = head.size();
    }
    std::string_view line(head.data() + pos, nl - pos);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    while (!line.empty() && (line.front() == ' ' || line.front() == '\t')) line.remove_prefix(1);
    pos = nl + 1;
    if (line.empty() || line.front() == '#') continue;
    ++meaningful;
    if (LooksLikeReceiverLine(line)) ++receiver;
  }
  if (meaningful == 0) {
    return MakeError(path, 0,
                     "no data: only blank or comment lines; expected a session.csv "
                     "header or receiver lines");
  }
  if (2 * receiver > meaningful) return SessionFormat::kReceiver;
  return internal::DetectNamedFormat(path, head);
}

namespace {

Result<Session> LoadSessionOrThrow(const std::string& path, const LoadOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) return MakeError(path, 0, "invalid load options: " + why);
  SessionFormat format = options.format;
  if (format == SessionFormat::kAuto) {
    auto detected = DetectSessionFormat(path);
    if (!detected.ok()) return detected.error();
    format = detected.value();
  }
  if (format == SessionFormat::kImuTk) {
    return MakeError(path, 0, "imu_tk input is two files: use LoadImuTk(acc, gyro)");
  }
  if (!options.topics.empty() && !IsBinaryLogFormat(format)) {
    return MakeError(
        path, 0,
        fmt::format("--topic {}: topics are chosen in ULog, MCAP, ROS bag and DataFlash input; "
                    "this is {} input",
                    options.topics.front(), SessionFormatName(format)));
  }
  Result<Session> session = MakeError(path, 0, "not loaded");
  if (format == SessionFormat::kULog) {
    session = internal::LoadULogSession(path, options);
  } else if (format == SessionFormat::kDataFlash) {
    session = internal::LoadDataFlashSession(path, options);
  } else if (IsBinaryLogFormat(format)) {
    session = internal::LoadRosSession(path, format, options);
  } else if (format != SessionFormat::kReceiver) {
    session =
        internal::LoadSessionCsv(path, options, /*allow_clean_path=*/true, /*hash=*/true, format);
  } else {
    // Hash the bytes on a second thread while the parser works.
    Result<std::string> digest = std::string();
    internal::RunBeside([&] { digest = Sha256File(path); },
                        [&] { session = internal::LoadReceiverCapture(path, options); });
    if (session.ok() && !digest.ok()) return digest.error();
    if (session.ok()) session.value().sha256 = digest.value();
  }
  if (!session.ok()) return session;
  Session out = std::move(session).value();
  if (options.derive_euler) {
    for (Tag& tag : out.tags) {
      if (std::string w = DeriveEulerIfAbsent(&tag); !w.empty()) {
        out.input.warnings.push_back(std::move(w));
      }
    }
  }
  return out;
}

}  // namespace

namespace {

// A stream (stdin, a FIFO, a character device), copied whole first (the loaders map their
// input, which a pipe does not allow); the session and its errors name it `name`, never the
// copy's path.
Result<Session> LoadStream(const internal::StdinCopyOptions& copy_options,
                           const LoadOptions& options) {
  auto copy = internal::CopyStdinToFile(copy_options);
  if (!copy.ok()) return copy.error();
  return internal::NamedAsStream(LoadSessionOrThrow(copy.value().path(), options),
                                 copy.value().path(), copy_options.display_name);
}

// A named path that is no regular file or directory (a FIFO, /dev/stdin on a pipe, a
// device): read as a stream, as `-` is. A terminal is refused (nobody is going to type a
// session); so is what cannot be opened.
Result<Session> LoadNamedStream(const std::string& path, const LoadOptions& options) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return MakeError(path, 0, std::string("cannot open: ") + std::strerror(errno));
  if (::isatty(fd)) {
    ::close(fd);
    return MakeError(path, 0,
                     "is a terminal (a console or serial port), not a session file: record a "
                     "receiver's port with `characterize capture --port DEV -o capture.txt` "
                     "and read the capture");
  }
  internal::StdinCopyOptions copy_options;
  copy_options.source_fd = fd;
  copy_options.display_name = path;
  Result<Session> session = LoadStream(copy_options, options);
  ::close(fd);
  return session;
}

}  // namespace

Result<Session> LoadSession(const std::string& path, const LoadOptions& options) {
  try {
    if (internal::IsStdinPath(path)) {
      internal::StdinCopyOptions stdin_options;
      return LoadStream(stdin_options, options);
    }
    struct stat st {};
    if (::stat(path.c_str(), &st) == 0 && !S_ISREG(st.st_mode) && !S_ISDIR(st.st_mode)) {
      return LoadNamedStream(path, options);
    }
    return LoadSessionOrThrow(path, options);
  } catch (const std::bad_alloc&) {
    return internal::OutOfMemoryError(path);
  }
}

std::string FormatSessionCsv(const Session& session, bool include_derived) {
  // Column union: numeric quantities then text columns, in first-seen order.
  std::vector<std::string> numeric;
  std::vector<std::string> text;
  for (const Tag& tag : session.tags) {
    for (const Quantity& q : tag.quantities) {
      if (q.origin == QuantityOrigin::kDerived && !include_derived) continue;
      if (std::find(numeric.begin(), numeric.end(), q.name) == numeric.end()) {
        numeric.push_back(q.name);
      }
    }
    for (const TextColumn& c : tag.text_columns) {
      if (std::find(text.begin(), text.end(), c.name) == text.end()) text.push_back(c.name);
    }
  }
  // Exact integer times stay exact: t_ns when every tag has them.
  const bool exact_time = !session.tags.empty() &&
                          std::all_of(session.tags.begin(), session.tags.end(),
                                      [](const Tag& t) { return t.t_ns.size() == t.t_s.size(); });
  std::string out;
  out.reserve(64 * 1024);
  auto it = std::back_inserter(out);
  fmt::format_to(it, exact_time ? "t_ns,sensor" : "t_s,sensor");
  for (const auto& n : numeric) fmt::format_to(it, ",{}", n);
  for (const auto& n : text) fmt::format_to(it, ",{}", n);
  out += '\n';

  struct Column {
    std::vector<const std::vector<double>*> numeric;
    std::vector<const std::vector<std::string>*> text;
  };
  std::vector<Column> columns(session.tags.size());
  for (size_t k = 0; k < session.tags.size(); ++k) {
    const Tag& tag = session.tags[k];
    for (const auto& n : numeric) {
      const Quantity* q = tag.Find(n);
      columns[k].numeric.push_back(q ? &q->values : nullptr);
    }
    for (const auto& n : text) {
      const std::vector<std::string>* values = nullptr;
      for (const TextColumn& c : tag.text_columns) {
        if (c.name == n) values = &c.values;
      }
      columns[k].text.push_back(values);
    }
  }
  // Merge the tags by time (then by sensor number: tags are sorted by sensor).
  using Head = std::pair<double, size_t>;  // (t, tag index)
  auto later = [](const Head& a, const Head& b) {
    return a.first != b.first ? a.first > b.first : a.second > b.second;
  };
  std::priority_queue<Head, std::vector<Head>, decltype(later)> heads(later);
  std::vector<size_t> cursor(session.tags.size(), 0);
  for (size_t k = 0; k < session.tags.size(); ++k) {
    if (!session.tags[k].t_s.empty()) heads.push({session.tags[k].t_s[0], k});
  }
  while (!heads.empty()) {
    const size_t k = heads.top().second;
    heads.pop();
    const Tag& tag = session.tags[k];
    const size_t i = cursor[k]++;
    if (exact_time) {
      fmt::format_to(it, "{},{}", tag.t_ns[i], tag.sensor);
    } else {
      fmt::format_to(it, "{},{}", tag.t_s[i], tag.sensor);
    }
    for (const auto* values : columns[k].numeric) {
      out += ',';
      if (values != nullptr && std::isfinite((*values)[i])) fmt::format_to(it, "{}", (*values)[i]);
    }
    for (const auto* values : columns[k].text) {
      out += ',';
      if (values != nullptr) out += (*values)[i];
    }
    out += '\n';
    if (cursor[k] < tag.t_s.size()) heads.push({tag.t_s[cursor[k]], k});
  }
  return out;
}

}  // namespace metro
