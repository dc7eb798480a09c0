// A PX4 ULog's IMU topics as a Session (docs/formats.md "PX4 ULog"): each instance
// (multi_id) of each chosen topic is one tag, numbered from 1 in the order of the topics
// and then of multi_id. Values are the logged floats, unconverted, in the canonical columns
// of their units (rad/s, m/s^2, degC); vehicle_imu's integrals become mean rates.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/parallel.hpp"
#include "io/session_internal.hpp"
#include "io/time_order.hpp"
#include "metro/core/file.hpp"
#include "metro/io/ulog.hpp"

namespace metro::internal {
namespace {

// One column of a tag: field[element], divided by dt_field * 1e-6 s when dt_field is set
// (vehicle_imu's integrals over their interval in us).
struct Channel {
  const char* column;
  const char* unit;
  const char* field;
  int element;
  const char* dt_field;
  bool optional;
};

struct TopicSpec {
  const char* topic;
  std::vector<Channel> channels;
};

const std::vector<TopicSpec>& TopicSpecs() {
  static const std::vector<TopicSpec> specs = {
      {"sensor_combined",
       {{"gx_rads", "rad/s", "gyro_rad", 0, nullptr, false},
        {"gy_rads", "rad/s", "gyro_rad", 1, nullptr, false},
        {"gz_rads", "rad/s", "gyro_rad", 2, nullptr, false},
        {"ax_mps2", "m/s^2", "accelerometer_m_s2", 0, nullptr, false},
        {"ay_mps2", "m/s^2", "accelerometer_m_s2", 1, nullptr, false},
        {"az_mps2", "m/s^2", "accelerometer_m_s2", 2, nullptr, false}}},
      {"sensor_accel",
       {{"ax_mps2", "m/s^2", "x", 0, nullptr, false},
        {"ay_mps2", "m/s^2", "y", 0, nullptr, false},
        {"az_mps2", "m/s^2", "z", 0, nullptr, false},
        {"temp_c", "degC", "temperature", 0, nullptr, true}}},
      {"sensor_gyro",
       {{"gx_rads", "rad/s", "x", 0, nullptr, false},
        {"gy_rads", "rad/s", "y", 0, nullptr, false},
        {"gz_rads", "rad/s", "z", 0, nullptr, false},
        {"temp_c", "degC", "temperature", 0, nullptr, true}}},
      {"vehicle_imu",
       {{"gx_rads", "rad/s", "delta_angle", 0, "delta_angle_dt", false},
        {"gy_rads", "rad/s", "delta_angle", 1, "delta_angle_dt", false},
        {"gz_rads", "rad/s", "delta_angle", 2, "delta_angle_dt", false},
        {"ax_mps2", "m/s^2", "delta_velocity", 0, "delta_velocity_dt", false},
        {"ay_mps2", "m/s^2", "delta_velocity", 1, "delta_velocity_dt", false},
        {"az_mps2", "m/s^2", "delta_velocity", 2, "delta_velocity_dt", false}}},
  };
  return specs;
}

const TopicSpec* FindTopicSpec(std::string_view topic) {
  for (const TopicSpec& s : TopicSpecs()) {
    if (topic == s.topic) return &s;
  }
  return nullptr;
}

std::string TopicList(const ULog& log, bool imu_only) {
  std::string out;
  for (const ULogTopicSummary& t : SummarizeULogTopics(log)) {
    if (imu_only && FindTopicSpec(t.topic) == nullptr) continue;
    out += fmt::format("{}{}[{}] ({} messages)", out.empty() ? "" : ", ", t.topic, t.multi_id,
                       t.message_count);
  }
  return out.empty() ? "none" : out;
}

// A --topic: NAME (every instance), NAME[K] or NAME:K (instance K only).
struct TopicChoice {
  std::string topic;
  int multi_id = -1;  // -1: every instance.
};

bool HasMessages(const ULog& log, const TopicChoice& c) {
  for (const ULogSubscription* s : log.Find(c.topic)) {
    if (s->message_count > 0 && (c.multi_id < 0 || s->multi_id == c.multi_id)) return true;
  }
  return false;
}

// NAME, NAME[K] or NAME:K; false when K is not a number 0..255.
bool ParseTopicChoice(const std::string& text, TopicChoice* c) {
  c->topic = text;
  c->multi_id = -1;
  size_t cut = text.find_first_of("[:");
  if (cut == std::string::npos) return true;
  std::string k = text.substr(cut + 1);
  if (text[cut] == '[') {
    if (k.empty() || k.back() != ']') return false;
    k.pop_back();
  }
  if (k.empty() || k.size() > 3 || k.find_first_not_of("0123456789") != std::string::npos ||
      std::stoi(k) > 255) {
    return false;
  }
  c->topic = text.substr(0, cut);
  c->multi_id = std::stoi(k);
  return true;
}

// --topic as given, or the default: sensor_combined, else sensor_accel + sensor_gyro.
Result<std::vector<TopicChoice>> ChooseTopics(const ULog& log, const LoadOptions& options) {
  std::vector<TopicChoice> topics;
  for (const std::string& t : options.topics) {
    TopicChoice c;
    if (!ParseTopicChoice(t, &c) || FindTopicSpec(c.topic) == nullptr) {
      return MakeError(log.path, 0,
                       fmt::format("--topic {}: not an IMU topic metro reads; expected "
                                   "sensor_combined, sensor_accel, sensor_gyro or vehicle_imu, "
                                   "optionally one instance as NAME[K] (this log's: {})",
                                   t, TopicList(log, true)));
    }
    if (!HasMessages(log, c)) {
      return MakeError(log.path, 0,
                       fmt::format("--topic {}: the log has no {} messages; its IMU topics: {} "
                                   "(`characterize topics {}` lists all)",
                                   t, t, TopicList(log, true), log.path));
    }
    for (const TopicChoice& earlier : topics) {
      if (earlier.topic == c.topic &&
          (earlier.multi_id < 0 || c.multi_id < 0 || earlier.multi_id == c.multi_id)) {
        return MakeError(log.path, 0,
                         fmt::format("--topic {}: that instance is chosen twice; each instance "
                                     "is one tag",
                                     t));
      }
    }
    topics.push_back(c);
  }
  if (!topics.empty()) return topics;
  if (HasMessages(log, TopicChoice{"sensor_combined"})) {
    return std::vector<TopicChoice>{TopicChoice{"sensor_combined"}};
  }
  for (const char* t : {"sensor_accel", "sensor_gyro"}) {
    if (HasMessages(log, TopicChoice{t})) topics.push_back(TopicChoice{t});
  }
  if (!topics.empty()) return topics;
  return MakeError(log.path, 0,
                   fmt::format("no sensor_combined, sensor_accel or sensor_gyro messages; IMU "
                               "topics: {}; choose one with --topic NAME (`characterize topics "
                               "{}` lists all)",
                               TopicList(log, true), log.path));
}

// A channel's field resolved in a format.
struct BoundChannel {
  const Channel* channel;
  const ULogField* field;
  const ULogField* dt;
};

struct TagBuild {
  Tag tag;
  std::vector<int64_t> t_us;
  std::vector<uint64_t> offset;  // Byte offset of each message read.
  std::vector<int64_t> number;   // Its 1-based number among the instance's messages.
  std::string time_field;
  std::string topic;
  int multi_id = 0;
  std::string label;    // "sensor_accel[1]: 6 messages", extended when paired.
  std::string name;     // "sensor_accel[1]", extended when paired (Tag::source_name).
  bool merged = false;  // Merged into another build (PairAccelGyro).
};

// sensor_accel[k] and sensor_gyro[k] sampled at the same instants (equal time sequences)
// are one IMU: their columns become one tag, the accelerometer's temperature kept (the
// gyroscope's beside it compared in a note). Instances with other times stay apart.
void PairAccelGyro(std::vector<TagBuild>* builds, std::vector<std::string>* notes) {
  for (TagBuild& a : *builds) {
    if (a.topic != "sensor_accel") continue;
    for (TagBuild& g : *builds) {
      if (g.topic != "sensor_gyro" || g.multi_id != a.multi_id || g.merged) continue;
      if (g.t_us != a.t_us) {
        notes->push_back(
            fmt::format("sensor_accel[{0}] and sensor_gyro[{0}] have different "
                        "sample times: two tags",
                        a.multi_id));
        continue;
      }
      const Quantity* a_temp = a.tag.Find("temp_c");
      for (Quantity& q : g.tag.quantities) {
        if (q.name != "temp_c" || a_temp == nullptr) {
          a.tag.quantities.push_back(std::move(q));
          a_temp = a.tag.Find("temp_c");
          continue;
        }
        double most = 0.0;
        for (size_t i = 0; i < q.values.size(); ++i) {
          most = std::max(most, std::fabs(q.values[i] - a_temp->values[i]));
        }
        notes->push_back(
            fmt::format("sensor_accel[{0}] and sensor_gyro[{0}] share their sample "
                        "times: one tag; temp_c is the accelerometer's (the "
                        "gyroscope's differs by at most {1} degC)",
                        a.multi_id, most));
      }
      a.label += " + " + g.label;
      a.name += " + " + g.name;
      g.merged = true;
    }
  }
  builds->erase(
      std::remove_if(builds->begin(), builds->end(), [](const TagBuild& b) { return b.merged; }),
      builds->end());
}

Result<std::vector<BoundChannel>> Bind(const ULog& log, const ULogSubscription& sub,
                                       const TopicSpec& spec) {
  const ULogFormat& format = log.FormatOf(sub);
  std::vector<BoundChannel> out;
  for (const Channel& c : spec.channels) {
    BoundChannel b{&c, format.Find(c.field), c.dt_field ? format.Find(c.dt_field) : nullptr};
    const bool field_ok =
        b.field != nullptr && b.field->kind != 0 && c.element < std::max(1, b.field->array_size);
    if (!field_ok || (c.dt_field != nullptr && (b.dt == nullptr || b.dt->kind == 0))) {
      if (c.optional) continue;
      return MakeError(log.path, 0,
                       fmt::format(
                           "format '{}' has no numeric field {}{} (it has: {}); expected "
                           "PX4's {} message",
                           format.name, field_ok ? c.dt_field : c.field,
                           field_ok ? "" : fmt::format("[{}]", c.element),
                           [&] {
                             std::string names;
                             for (const ULogField& f : format.fields) {
                               names += (names.empty() ? "" : " ") + f.name;
                             }
                             return names;
                           }(),
                           spec.topic));
    }
    out.push_back(b);
  }
  return out;
}

// Reads message i of `sub` into the row; "" or what is wrong with it.
std::string ReadRow(const ULog& log, const ULogSubscription& sub, size_t i, const ULogField& time,
                    const std::vector<BoundChannel>& channels, uint64_t* t_us,
                    std::vector<double>* row) {
  const uint64_t at = sub.data_offsets[i];
  const uint16_t size = sub.data_sizes[i];
  if (!ReadULogU64(log, at, size, time, t_us)) return "no " + time.name + " in the message";
  row->clear();
  for (const BoundChannel& b : channels) {
    double v = 0.0;
    if (!ReadULogValue(log, at, size, *b.field, b.channel->element, &v)) {
      return fmt::format("{} lies past the message's {} bytes", b.field->name, size);
    }
    if (b.dt != nullptr) {
      double dt_us = 0.0;
      if (!ReadULogValue(log, at, size, *b.dt, 0, &dt_us) || !(dt_us > 0.0)) {
        return fmt::format("{} = {} us: expected a positive integration interval", b.dt->name,
                           dt_us);
      }
      v /= dt_us * 1e-6;  // Mean rate over the interval.
    }
    if (!std::isfinite(v)) {
      return fmt::format("{}[{}] is {}: expected a finite number", b.field->name,
                         b.channel->element, v);
    }
    row->push_back(v);
  }
  return "";
}

// One tag from one subscription. Strict: the first bad message stops the load.
Result<TagBuild> ReadTag(const ULog& log, const ULogSubscription& sub, const TopicSpec& spec,
                         const LoadOptions& options, Session* session) {
  auto bound = Bind(log, sub, spec);
  if (!bound.ok()) return bound.error();
  const ULogFormat& format = log.FormatOf(sub);
  TagBuild out;
  const ULogField* time = format.Find("timestamp_sample");
  if (time == nullptr) time = format.Find("timestamp");
  if (time == nullptr) {
    return MakeError(log.path, 0, fmt::format("format '{}' has no timestamp field", format.name));
  }
  out.time_field = time->name;
  for (const BoundChannel& b : bound.value()) {
    out.tag.quantities.push_back(
        Quantity{b.channel->column, b.channel->unit, QuantityOrigin::kFile, {}});
    out.tag.quantities.back().values.reserve(sub.data_offsets.size());
  }
  std::vector<double> row;
  for (size_t i = 0; i < sub.data_offsets.size(); ++i) {
    uint64_t t_us = 0;
    std::string problem = ReadRow(log, sub, i, *time, bound.value(), &t_us, &row);
    if (problem.empty() &&
        t_us > static_cast<uint64_t>(std::numeric_limits<int64_t>::max() / 1000)) {
      problem = fmt::format("{} = {} us: beyond the range metro keeps in ns", time->name, t_us);
    }
    if (!problem.empty()) {
      const Error e =
          MakeError(log.path, 0,
                    fmt::format("byte offset {}: {}[{}] message {}: {}", sub.data_offsets[i] - 5,
                                sub.topic, sub.multi_id, i + 1, problem));
      if (!options.lenient) return e;
      ++session->rejected_rows;
      if (session->rejected_lines.size() < options.max_rejected_kept) {
        session->rejected_lines.push_back(sub.message_index[i]);
        session->rejected_reasons.push_back(e.ToString());
      }
      continue;
    }
    out.t_us.push_back(static_cast<int64_t>(t_us));
    out.offset.push_back(sub.data_offsets[i] - 5);
    out.number.push_back(static_cast<int64_t>(i) + 1);
    out.tag.line.push_back(sub.message_index[i]);
    for (size_t k = 0; k < row.size(); ++k) out.tag.quantities[k].values.push_back(row[k]);
  }
  return out;
}

// The instance's times strictly increasing (PlanTimeOrder, shared with the ROS logs): sorted
// with repeats after the first dropped, or refused (--time-order refuse). Counts in the notes.
Status OrderTimes(const ULog& log, const LoadOptions& options, TagBuild* b,
                  std::vector<std::string>* notes) {
  const TimeOrderPlan plan = PlanTimeOrder(b->t_us);
  if (plan.in_order()) return Status::Ok();
  if (options.time_order == LoadOptions::TimeOrder::kRefuse) {
    const size_t i = plan.first_not_after;
    return MakeError(log.path, 0,
                     fmt::format("byte offset {}: {} message {}: {} {} us is not after the "
                                 "previous message's {} us; expected increasing times "
                                 "(--time-order sort sorts them)",
                                 b->offset[i], b->name, b->number[i], b->time_field, b->t_us[i],
                                 b->t_us[i - 1]));
  }
  Permute(plan.keep, &b->t_us);
  Permute(plan.keep, &b->offset);
  Permute(plan.keep, &b->number);
  Permute(plan.keep, &b->tag.line);
  for (Quantity& q : b->tag.quantities) Permute(plan.keep, &q.values);
  notes->push_back(fmt::format(
      "{}: {} messages out of {} order, sorted; {} repeated {} dropped (the first in the "
      "file kept) (--time-order sort)",
      b->name, plan.late, b->time_field, plan.repeats, b->time_field));
  return Status::Ok();
}

// sensor_combined's accelerometer was sampled at timestamp + accelerometer_timestamp_relative;
// the tag keeps the gyroscope's time for both. What the offsets were, for the notes; a
// warning when PX4 marked messages as without a new accelerometer sample (INT32_MAX).
void AccelRelativeNotes(const ULog& log, InputDialect* in) {
  constexpr double kInvalid = 2147483647.0;  // PX4's RELATIVE_TIMESTAMP_INVALID.
  for (const ULogSubscription* sub : log.Find("sensor_combined")) {
    const ULogField* f = log.FormatOf(*sub).Find("accelerometer_timestamp_relative");
    if (f == nullptr || sub->data_offsets.empty()) continue;
    double lo = kInvalid, hi = -kInvalid;
    int64_t invalid = 0;
    for (size_t i = 0; i < sub->data_offsets.size(); ++i) {
      double v = 0.0;
      if (!ReadULogValue(log, sub->data_offsets[i], sub->data_sizes[i], *f, 0, &v)) continue;
      if (v == kInvalid) {
        ++invalid;
        continue;
      }
      lo = std::min(lo, v);
      hi = std::max(hi, v);
    }
    if (lo <= hi) {
      in->notes.push_back(fmt::format(
          "sensor_combined[{}]: accelerometer_timestamp_relative {} us; the accelerometer "
          "columns carry the gyroscope's time",
          sub->multi_id,
          lo == hi ? fmt::format("{:.0f}", lo) : fmt::format("from {:.0f} to {:.0f}", lo, hi)));
    }
    if (invalid > 0) {
      in->warnings.push_back(fmt::format(
          "sensor_combined[{}]: {} messages without a new accelerometer sample "
          "(accelerometer_timestamp_relative = 2147483647): their ax_mps2..az_mps2 are what "
          "the message holds, not a new measurement",
          sub->multi_id, invalid));
    }
  }
}

void AddNotes(const ULog& log, const std::vector<TopicChoice>& topics, Session* session) {
  InputDialect& in = session->input;
  in.notes.push_back(fmt::format(
      "PX4 ULog version {}: t_s = (t - t0) * 1e-6 s, t the time field each sensor above names "
      "[us, the autopilot's boot clock], t0 = {} us (the first sample read; logging started at "
      "{} us); line numbers are 1-based message indexes in the file",
      log.version, in.time_origin_ns / 1000, log.start_time_us));
  for (const TopicChoice& choice : topics) {
    const std::string& t = choice.topic;
    if (t == "sensor_combined") {
      in.notes.push_back(
          "sensor_combined: gyro_rad -> gx_rads..gz_rads, accelerometer_m_s2 -> ax_mps2..az_mps2, "
          "both at the gyroscope's timestamp (the accelerometer's own time is timestamp + "
          "accelerometer_timestamp_relative, not applied)");
      AccelRelativeNotes(log, &in);
    } else if (t == "vehicle_imu") {
      in.notes.push_back(
          "vehicle_imu: gx_rads.. = delta_angle / (delta_angle_dt * 1e-6 s), ax_mps2.. = "
          "delta_velocity / (delta_velocity_dt * 1e-6 s): mean rates over each integration "
          "interval");
    }
  }
  if (log.dropout_count > 0) {
    in.warnings.push_back(
        fmt::format("{} logging dropouts ('O' messages), {} ms in all, the "
                    "longest {} ms: data the logger lost",
                    log.dropout_count, log.dropout_total_ms, log.dropout_max_ms));
  }
  if (log.cut_bytes > 0) {
    in.notes.push_back(
        fmt::format("{} bytes of a message cut where appended data starts", log.cut_bytes));
  }
  if (log.truncated_bytes > 0) {
    in.warnings.push_back(
        fmt::format("truncated file: the last {} bytes are an incomplete "
                    "message, skipped (--lenient)",
                    log.truncated_bytes));
  }
  if (log.unsubscribed_data_count > 0) {
    in.warnings.push_back(
        fmt::format("{} data messages of ids no 'A' message added, skipped "
                    "(--lenient)",
                    log.unsubscribed_data_count));
  }
}

Result<Session> LoadULogSessionFrom(ULog log, const LoadOptions& options) {
  auto topics = ChooseTopics(log, options);
  if (!topics.ok()) return topics.error();
  Session session;
  session.path = log.path;
  session.format = SessionFormat::kULog;
  session.columns = {"t_s", "sensor"};
  for (size_t i = 0; i < log.problems.size(); ++i) {
    ++session.rejected_rows;
    if (session.rejected_reasons.size() < options.max_rejected_kept) {
      session.rejected_lines.push_back(log.problem_messages[i]);
      session.rejected_reasons.push_back(log.problems[i]);
    }
  }
  std::vector<TagBuild> builds;
  for (const TopicChoice& choice : topics.value()) {
    const std::string& topic = choice.topic;
    for (const ULogSubscription* sub : log.Find(topic)) {
      if (sub->message_count == 0) continue;
      if (choice.multi_id >= 0 && sub->multi_id != choice.multi_id) continue;
      auto build = ReadTag(log, *sub, *FindTopicSpec(topic), options, &session);
      if (!build.ok()) return build.error();
      build.value().topic = topic;
      build.value().multi_id = sub->multi_id;
      build.value().name = fmt::format("{}[{}]", topic, sub->multi_id);
      build.value().label = fmt::format("{}[{}] ({} messages, time from {})", topic, sub->multi_id,
                                        sub->message_count, build.value().time_field);
      builds.push_back(std::move(build).value());
    }
  }
  std::vector<std::string> order_notes;
  for (TagBuild& b : builds) {
    if (Status s = OrderTimes(log, options, &b, &order_notes); !s.ok()) return s.error();
    session.rows += static_cast<int64_t>(b.t_us.size());
  }
  std::vector<std::string> pair_notes;
  PairAccelGyro(&builds, &pair_notes);
  for (size_t k = 0; k < builds.size(); ++k) {
    builds[k].tag.sensor = static_cast<int>(k) + 1;
    builds[k].tag.source_name = builds[k].name;
    session.input.notes.push_back(fmt::format("sensor {} = {}", k + 1, builds[k].label));
  }
  session.input.notes.insert(session.input.notes.end(), pair_notes.begin(), pair_notes.end());
  session.input.notes.insert(session.input.notes.end(), order_notes.begin(), order_notes.end());
  int64_t t0_us = std::numeric_limits<int64_t>::max();
  for (const TagBuild& b : builds) {
    if (!b.t_us.empty()) t0_us = std::min(t0_us, b.t_us.front());
  }
  if (t0_us == std::numeric_limits<int64_t>::max()) {
    return MakeError(log.path, 0, "no IMU message could be read (all rejected)");
  }
  InputDialect& in = session.input;
  in.header_line = 0;
  in.time_source = builds.front().time_field;
  in.time_unit = "us";
  in.time_integer = true;
  in.time_origin_ns = t0_us * 1000;
  for (TagBuild& b : builds) {
    for (const int64_t t : b.t_us) {
      b.tag.t_ns.push_back(t * 1000);
      b.tag.t_s.push_back(static_cast<double>(t - t0_us) * 1e-6);
    }
    b.tag.counts.frames = b.tag.counts.fresh = static_cast<int64_t>(b.t_us.size());
    for (const Quantity& q : b.tag.quantities) {
      if (std::find(session.columns.begin(), session.columns.end(), q.name) ==
          session.columns.end()) {
        session.columns.push_back(q.name);
      }
    }
    session.tags.push_back(std::move(b.tag));
  }
  session.rows += session.rejected_rows;
  AddNotes(log, topics.value(), &session);
  return session;
}

}  // namespace

Result<Session> LoadULogSession(const std::string& path, const LoadOptions& options) {
  ULogReadOptions read;
  read.lenient = options.lenient;
  for (const TopicSpec& s : TopicSpecs()) read.keep_topics.push_back(s.topic);
  // The file is hashed on a second thread while it is read and decoded.
  Result<std::string> digest = std::string();
  Result<Session> session = MakeError(path, 0, "not loaded");
  RunBeside([&] { digest = Sha256File(path); },
            [&] {
              auto log = ReadULog(path, read);
              session = log.ok() ? LoadULogSessionFrom(std::move(log).value(), options)
                                 : Result<Session>(log.error());
            });
  if (!session.ok()) return session;
  if (!digest.ok()) return digest.error();
  session.value().sha256 = digest.value();
  return session;
}

}  // namespace metro::internal
