// An ArduPilot DataFlash log's IMU messages as a Session (docs/formats.md "ArduPilot
// DataFlash"): IMU, IMU2 and IMU3 (older logs: one message type per IMU) or IMU with an
// instance column I (newer logs: one stream per instance), each stream one tag, numbered
// from 1 in the order of the types and then of the instances. Values are the logged floats,
// unconverted: GyrX..GyrZ -> gx_rads..gz_rads [rad/s], AccX..AccZ -> ax_mps2..az_mps2
// [m/s^2], T -> temp_c [degC]; time TimeUS [us since the autopilot booted].
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/parallel.hpp"
#include "io/session_internal.hpp"
#include "io/time_order.hpp"
#include "metro/core/file.hpp"
#include "metro/io/dataflash.hpp"

namespace metro::internal {
namespace {

constexpr const char* kImuNames[] = {"IMU", "IMU2", "IMU3"};
constexpr const char* kFields[] = {"GyrX", "GyrY", "GyrZ", "AccX", "AccY", "AccZ", "T"};
constexpr const char* kColumns[] = {"gx_rads", "gy_rads", "gz_rads", "ax_mps2",
                                    "ay_mps2", "az_mps2", "temp_c"};
constexpr const char* kUnits[] = {"rad/s", "rad/s", "rad/s", "m/s^2", "m/s^2", "m/s^2", "degC"};

// One IMU's messages: a type, or one instance of a type with an I column.
struct Stream {
  std::string name;  // "IMU2", or "IMU[1]".
  std::vector<int64_t> t_us;
  std::vector<uint64_t> offset;
  std::vector<uint32_t> line;  // 1-based message index in the file.
  std::vector<double> columns[7];
  bool has_temperature = false;
};

std::string ImuList(const DataFlash& log) {
  std::string out;
  for (const char* name : kImuNames) {
    const DataFlashFormat* f = log.Find(name);
    if (f == nullptr || f->message_count == 0) continue;
    out += fmt::format("{}{} ({} messages{})", out.empty() ? "" : ", ", name, f->message_count,
                       f->Find("I") != nullptr ? ", instances by its I column" : "");
  }
  return out.empty() ? "none" : out;
}

// --topic NAME (IMU, IMU2, IMU3) or NAME[K] (instance K of a type with an I column).
struct Choice {
  std::string name;
  int instance = -1;
};

Result<std::vector<Choice>> Choose(const DataFlash& log, const LoadOptions& options) {
  std::vector<Choice> out;
  for (const std::string& t : options.topics) {
    Choice c{t, -1};
    const size_t open = t.find('[');
    if (open != std::string::npos && t.back() == ']' && t.size() - open > 2 &&
        t.size() - open < 6 && t.find_first_not_of("0123456789", open + 1) == t.size() - 1) {
      c.name = t.substr(0, open);
      c.instance = std::stoi(t.substr(open + 1));
    }
    const DataFlashFormat* f = log.Find(c.name);
    const bool imu =
        std::find(std::begin(kImuNames), std::end(kImuNames), c.name) != std::end(kImuNames);
    if (!imu || f == nullptr || f->message_count == 0 ||
        (c.instance >= 0 && f->Find("I") == nullptr)) {
      return MakeError(
          log.path, 0,
          fmt::format("--topic {}: expected one of the log's IMU messages: {} (NAME[K] "
                      "for instance K of a message with an I column; `characterize "
                      "topics {}` lists all)",
                      t, ImuList(log), log.path));
    }
    for (const Choice& earlier : out) {
      if (earlier.name == c.name &&
          (earlier.instance < 0 || c.instance < 0 || earlier.instance == c.instance)) {
        return MakeError(log.path, 0,
                         fmt::format("--topic {}: chosen twice; each IMU is one tag", t));
      }
    }
    out.push_back(c);
  }
  if (!out.empty()) return out;
  for (const char* name : kImuNames) {
    const DataFlashFormat* f = log.Find(name);
    if (f != nullptr && f->message_count > 0) out.push_back(Choice{name, -1});
  }
  if (out.empty()) {
    return MakeError(log.path, 0,
                     "no IMU, IMU2 or IMU3 messages; expected an ArduPilot log with IMU logging "
                     "(`characterize topics " +
                         log.path + "` lists its messages)");
  }
  return out;
}

// Reads one type's messages into streams (one, or one per instance). Strict: the first bad
// message stops the load; lenient: it is counted and skipped.
Status ReadType(const DataFlash& log, const Choice& c, const LoadOptions& options,
                std::vector<Stream>* streams, Session* session) {
  const DataFlashFormat& f = *log.Find(c.name);
  const DataFlashField* time = f.Find("TimeUS");
  const DataFlashField* instance = f.Find("I");
  const DataFlashField* fields[7];
  for (int k = 0; k < 7; ++k) {
    fields[k] = f.Find(kFields[k]);
    if (fields[k] == nullptr && k < 6) {
      return MakeError(log.path, 0,
                       fmt::format("byte offset {}: FMT of {} has no {} column; expected "
                                   "TimeUS, GyrX..GyrZ, AccX..AccZ (and T)",
                                   f.fmt_offset, c.name, kFields[k]));
    }
  }
  if (time == nullptr || std::string_view("QqIi").find(time->type) == std::string_view::npos) {
    return MakeError(log.path, 0,
                     fmt::format("byte offset {}: FMT of {} has no integer TimeUS column; "
                                 "expected the time in us",
                                 f.fmt_offset, c.name));
  }
  const size_t first = streams->size();
  for (size_t i = 0; i < f.offsets.size(); ++i) {
    const uint64_t at = f.offsets[i];
    uint64_t t_us = 0, k = 0;
    ReadDataFlashU64(log, at, *time, &t_us);
    if (instance != nullptr) ReadDataFlashU64(log, at, *instance, &k);
    if (c.instance >= 0 && static_cast<int>(k) != c.instance) continue;
    const std::string name = instance != nullptr ? fmt::format("{}[{}]", c.name, k) : c.name;
    auto it = std::find_if(streams->begin() + static_cast<std::ptrdiff_t>(first), streams->end(),
                           [&](const Stream& s) { return s.name == name; });
    if (it == streams->end()) {
      streams->emplace_back();
      streams->back().name = name;
      streams->back().has_temperature = fields[6] != nullptr;
      it = streams->end() - 1;
    }
    double row[7] = {};
    std::string problem;
    for (int j = 0; j < 7 && problem.empty(); ++j) {
      if (fields[j] == nullptr) continue;
      ReadDataFlashValue(log, at, *fields[j], &row[j]);
      if (!std::isfinite(row[j])) {
        problem = fmt::format("{} = {}: expected a finite number", kFields[j], row[j]);
      }
    }
    if (problem.empty() &&
        t_us > static_cast<uint64_t>(std::numeric_limits<int64_t>::max() / 1000)) {
      problem = fmt::format("TimeUS = {} us: beyond the range metro keeps in ns", t_us);
    }
    if (!problem.empty()) {
      const Error e = MakeError(
          log.path, 0,
          fmt::format("byte offset {}: {} message {}: {}", at, name, it->t_us.size() + 1, problem));
      if (!options.lenient) return e;
      ++session->rejected_rows;
      if (session->rejected_lines.size() < options.max_rejected_kept) {
        session->rejected_lines.push_back(f.indexes[i]);
        session->rejected_reasons.push_back(e.ToString());
      }
      continue;
    }
    it->t_us.push_back(static_cast<int64_t>(t_us));
    it->offset.push_back(at);
    it->line.push_back(static_cast<uint32_t>(f.indexes[i]));
    for (int j = 0; j < 7; ++j) it->columns[j].push_back(row[j]);
  }
  if (c.instance >= 0 && streams->size() == first) {
    return MakeError(log.path, 0,
                     fmt::format("--topic {}[{}]: no message of that instance; the log's IMU "
                                 "messages: {}",
                                 c.name, c.instance, ImuList(log)));
  }
  return Status::Ok();
}

// Times strictly increasing per stream (PlanTimeOrder, as the ROS logs and ULog).
Status OrderTimes(const DataFlash& log, const LoadOptions& options, Stream* s,
                  std::vector<std::string>* notes) {
  const TimeOrderPlan plan = PlanTimeOrder(s->t_us);
  if (plan.in_order()) return Status::Ok();
  if (options.time_order == LoadOptions::TimeOrder::kRefuse) {
    const size_t i = plan.first_not_after;
    return MakeError(log.path, 0,
                     fmt::format("byte offset {}: {} message {}: TimeUS {} us is not after the "
                                 "previous message's {} us; expected increasing times "
                                 "(--time-order sort sorts them)",
                                 s->offset[i], s->name, i + 1, s->t_us[i], s->t_us[i - 1]));
  }
  Permute(plan.keep, &s->t_us);
  Permute(plan.keep, &s->offset);
  Permute(plan.keep, &s->line);
  for (std::vector<double>& c : s->columns) Permute(plan.keep, &c);
  notes->push_back(fmt::format(
      "{}: {} messages out of TimeUS order, sorted; {} repeated TimeUS dropped (the first in "
      "the file kept) (--time-order sort)",
      s->name, plan.late, plan.repeats));
  return Status::Ok();
}

Tag MakeTag(Stream& s, int sensor, int64_t t0_us) {
  Tag tag;
  tag.sensor = sensor;
  tag.source_name = s.name;
  tag.line = std::move(s.line);
  for (int64_t t : s.t_us) {
    tag.t_ns.push_back(t * 1000);
    tag.t_s.push_back(static_cast<double>(t - t0_us) * 1e-6);
  }
  for (int k = 0; k < (s.has_temperature ? 7 : 6); ++k) {
    tag.quantities.push_back(
        Quantity{kColumns[k], kUnits[k], QuantityOrigin::kFile, std::move(s.columns[k])});
  }
  tag.counts.frames = tag.counts.fresh = static_cast<int64_t>(s.t_us.size());
  return tag;
}

void AddNotes(const DataFlash& log, const LoadOptions& options, Session* session) {
  InputDialect& in = session->input;
  in.notes.insert(in.notes.begin(),
                  fmt::format("ArduPilot DataFlash: t_s = (t - t0) * 1e-6 s, t the message's "
                              "TimeUS [us since the autopilot booted], t0 = {} us (the first "
                              "sample read); line numbers are 1-based message indexes in the file",
                              in.time_origin_ns / 1000));
  if (log.truncated_bytes > 0) {
    in.warnings.push_back(fmt::format(
        "truncated file: the last {} bytes are an incomplete message, skipped (--lenient)",
        log.truncated_bytes));
  }
  if (log.skipped_bytes > 0) {
    in.warnings.push_back(fmt::format(
        "{} bytes that were not a message skipped to the next message header (--lenient)",
        log.skipped_bytes));
  }
  for (const std::string& p : log.problems) {
    ++session->rejected_rows;
    if (session->rejected_reasons.size() < options.max_rejected_kept) {
      session->rejected_lines.push_back(0);
      session->rejected_reasons.push_back(p);
    }
  }
}

Result<Session> BuildSession(const DataFlash& log, const LoadOptions& options) {
  auto choices = Choose(log, options);
  if (!choices.ok()) return choices.error();
  Session session;
  session.path = log.path;
  session.format = SessionFormat::kDataFlash;
  session.columns = {"t_s", "sensor"};
  std::vector<Stream> streams;
  for (const Choice& c : choices.value()) {
    if (Status s = ReadType(log, c, options, &streams, &session); !s.ok()) return s.error();
  }
  std::vector<std::string> notes;
  int64_t t0_us = std::numeric_limits<int64_t>::max();
  for (Stream& s : streams) {
    if (Status st = OrderTimes(log, options, &s, &notes); !st.ok()) return st.error();
    if (!s.t_us.empty()) t0_us = std::min(t0_us, s.t_us.front());
  }
  if (t0_us == std::numeric_limits<int64_t>::max()) {
    return MakeError(log.path, 0, "no IMU message could be read (all rejected)");
  }
  InputDialect& in = session.input;
  in.header_line = 0;
  in.time_source = "TimeUS";
  in.time_unit = "us";
  in.time_integer = true;
  in.time_origin_ns = t0_us * 1000;
  for (size_t k = 0; k < streams.size(); ++k) {
    in.notes.push_back(fmt::format("sensor {} = {} ({} messages)", k + 1, streams[k].name,
                                   streams[k].t_us.size()));
    session.rows += static_cast<int64_t>(streams[k].t_us.size());
    session.tags.push_back(MakeTag(streams[k], static_cast<int>(k) + 1, t0_us));
    for (const Quantity& q : session.tags.back().quantities) {
      if (std::find(session.columns.begin(), session.columns.end(), q.name) ==
          session.columns.end()) {
        session.columns.push_back(q.name);
      }
    }
  }
  in.notes.insert(in.notes.end(), notes.begin(), notes.end());
  AddNotes(log, options, &session);
  session.rows += session.rejected_rows;
  return session;
}

}  // namespace

Result<Session> LoadDataFlashSession(const std::string& path, const LoadOptions& options) {
  DataFlashReadOptions read;
  read.lenient = options.lenient;
  read.keep_names.assign(std::begin(kImuNames), std::end(kImuNames));
  // The file is hashed on a second thread while it is read and decoded.
  Result<std::string> digest = std::string();
  Result<Session> session = MakeError(path, 0, "not loaded");
  RunBeside([&] { digest = Sha256File(path); },
            [&] {
              auto log = ReadDataFlash(path, read);
              session =
                  log.ok() ? BuildSession(log.value(), options) : Result<Session>(log.error());
            });
  if (!session.ok()) return session;
  if (!digest.ok()) return digest.error();
  session.value().sha256 = digest.value();
  return session;
}

}  // namespace metro::internal
