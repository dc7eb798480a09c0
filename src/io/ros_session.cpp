// An MCAP file's or a ROS bag's sensor_msgs/Imu topics as a Session (docs/formats.md "ROS
// bags and MCAP"): each chosen topic is one tag, numbered from 1 in the order of --topic
// (or of the log's connections). Values are the message's float64, unconverted, in the
// canonical columns of their units: angular_velocity -> gx_rads..gz_rads [rad/s],
// linear_acceleration -> ax_mps2..az_mps2 [m/s^2], orientation -> qw qx qy qz when every
// message has one (orientation_covariance[0] != -1, REP 145 / the message's comment).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/parallel.hpp"
#include "io/imu_message.hpp"
#include "io/ros_log_internal.hpp"
#include "io/session_internal.hpp"
#include "io/time_order.hpp"
#include "metro/core/file.hpp"
#include "metro/io/ros_log.hpp"

namespace metro::internal {
namespace {

// The messages of one topic, decoded, in file order.
struct TopicData {
  std::string topic;
  std::vector<int64_t> t_ns;           // The sample time chosen (header.stamp or log time).
  std::vector<int64_t> index;          // 1-based message index in the file.
  std::vector<uint64_t> offset;        // Byte offset of the record (or its chunk).
  std::vector<double> columns[10];     // qw qx qy qz, gx gy gz, ax ay az.
  int64_t with_orientation = 0;        // Messages whose orientation_covariance[0] != -1.
  double covariance[3][9] = {};        // The first message's orientation, gyro, accel ones.
  int64_t covariance_changes[3] = {};  // Messages whose covariance differs from the first's.
};

constexpr const char* kColumns[10] = {"qw",      "qx",      "qy",      "qz",      "gx_rads",
                                      "gy_rads", "gz_rads", "ax_mps2", "ay_mps2", "az_mps2"};
constexpr const char* kUnits[10] = {"1",     "1",     "1",     "1",     "rad/s",
                                    "rad/s", "rad/s", "m/s^2", "m/s^2", "m/s^2"};

bool Chosen(const LoadOptions& options, const std::string& topic) {
  return options.topics.empty() ||
         std::find(options.topics.begin(), options.topics.end(), topic) != options.topics.end();
}

class Collector {
 public:
  Collector(const LoadOptions& options, Session* session) : options_(options), session_(session) {}

  Status Visit(const RosLog& log, const RosMessageView& m);
  std::vector<TopicData>& topics() { return topics_; }

 private:
  TopicData* DataOf(const RosLog& log, size_t connection);
  void Add(TopicData* d, const ImuMessage& msg, const RosMessageView& m);

  const LoadOptions& options_;
  Session* session_;
  std::vector<TopicData> topics_;
  std::vector<int> of_connection_;  // Connection index -> topics_ index, -1 skipped, -2 unseen.
};

TopicData* Collector::DataOf(const RosLog& log, size_t connection) {
  if (of_connection_.size() <= connection) of_connection_.resize(connection + 1, -2);
  int& k = of_connection_[connection];
  if (k == -2) {
    const RosConnection& c = log.connections[connection];
    k = -1;
    if (IsImuType(c.type) && Chosen(options_, c.topic)) {
      auto it = std::find_if(topics_.begin(), topics_.end(),
                             [&](const TopicData& d) { return d.topic == c.topic; });
      k = static_cast<int>(it - topics_.begin());
      if (it == topics_.end()) {
        topics_.emplace_back();
        topics_.back().topic = c.topic;
      }
    }
  }
  return k < 0 ? nullptr : &topics_[static_cast<size_t>(k)];
}

void Collector::Add(TopicData* d, const ImuMessage& msg, const RosMessageView& m) {
  d->t_ns.push_back(options_.ros_time == LoadOptions::RosTime::kReceive ? m.log_time_ns
                                                                        : msg.stamp_ns);
  d->index.push_back(m.index);
  d->offset.push_back(m.record_offset);
  const double* q = msg.orientation_xyzw;
  const double row[10] = {q[3],
                          q[0],
                          q[1],
                          q[2],
                          msg.angular_velocity_rads[0],
                          msg.angular_velocity_rads[1],
                          msg.angular_velocity_rads[2],
                          msg.linear_acceleration_mps2[0],
                          msg.linear_acceleration_mps2[1],
                          msg.linear_acceleration_mps2[2]};
  for (int k = 0; k < 10; ++k) d->columns[k].push_back(row[k]);
  if (msg.orientation_covariance[0] != -1.0) ++d->with_orientation;
  const double* cov[3] = {msg.orientation_covariance, msg.angular_velocity_covariance,
                          msg.linear_acceleration_covariance};
  const bool first = d->t_ns.size() == 1;
  for (int k = 0; k < 3; ++k) {
    if (first) {
      std::copy(cov[k], cov[k] + 9, d->covariance[k]);
    } else if (!std::equal(cov[k], cov[k] + 9, d->covariance[k])) {
      ++d->covariance_changes[k];
    }
  }
}

Status Collector::Visit(const RosLog& log, const RosMessageView& m) {
  TopicData* d = DataOf(log, m.connection);
  if (d == nullptr) return Status::Ok();
  const RosConnection& c = log.connections[m.connection];
  ImuMessage msg;
  std::string why;
  if (c.encoding == "cdr") {
    why = DecodeImuCdr(m.data, &msg);
  } else if (c.encoding == "ros1") {
    why = c.md5sum.empty() || c.md5sum == kRos1ImuMd5
              ? DecodeImuRos1(m.data, &msg)
              : fmt::format(
                    "the connection's md5sum {} is not sensor_msgs/Imu's {}: another "
                    "definition of the type",
                    c.md5sum, kRos1ImuMd5);
  } else {
    why = fmt::format("message encoding \"{}\": expected \"cdr\" (ROS 2) or \"ros1\"", c.encoding);
  }
  if (why.empty()) {
    Add(d, msg, m);
    return Status::Ok();
  }
  const Error e = MakeError(log.path, 0,
                            fmt::format("{} {}: message {} ({} {}): {}", log.offset_name,
                                        m.record_offset, m.index, c.topic, c.type, why));
  if (!options_.lenient) return e;
  ++session_->rejected_rows;
  if (session_->rejected_lines.size() < options_.max_rejected_kept) {
    session_->rejected_lines.push_back(m.index);
    session_->rejected_reasons.push_back(e.ToString());
  }
  return Status::Ok();
}

// "a (type, N messages), b (...)" for the topics `keep` accepts.
template <typename Keep>
std::string TopicList(const RosLog& log, Keep keep) {
  std::string out;
  for (const RosConnection& c : log.connections) {
    if (!keep(c) || out.find(c.topic + " (") != std::string::npos) continue;
    int64_t n = 0;
    for (const RosConnection* same : log.Find(c.topic)) n += same->message_count;
    out += fmt::format("{}{} ({}, {} messages)", out.empty() ? "" : ", ", c.topic, c.type, n);
  }
  return out.empty() ? "none" : out;
}

// The topics read: --topic as given (each must exist and be sensor_msgs/Imu), or the one
// IMU topic of the log.
Status CheckTopics(const RosLog& log, const LoadOptions& options,
                   const std::vector<TopicData>& data) {
  auto any = [](const RosConnection&) { return true; };
  auto imu = [](const RosConnection& c) { return IsImuType(c.type); };
  for (const std::string& t : options.topics) {
    const auto found = log.Find(t);
    if (found.empty()) {
      return MakeError(log.path, 0,
                       fmt::format("--topic {}: no such topic; expected one of the log's: {}", t,
                                   TopicList(log, any)));
    }
    if (!IsImuType(found.front()->type)) {
      return MakeError(log.path, 0,
                       fmt::format("--topic {}: its messages are {}; expected sensor_msgs/Imu "
                                   "(the log's IMU topics: {})",
                                   t, found.front()->type, TopicList(log, imu)));
    }
    if (std::count(options.topics.begin(), options.topics.end(), t) > 1) {
      return MakeError(log.path, 0,
                       fmt::format("--topic {}: chosen twice; each topic is one tag", t));
    }
  }
  if (data.empty()) {
    return MakeError(log.path, 0,
                     fmt::format("no sensor_msgs/Imu messages; expected an IMU topic (the log's "
                                 "topics: {})",
                                 TopicList(log, any)));
  }
  if (options.topics.empty() && data.size() > 1) {
    return MakeError(log.path, 0,
                     fmt::format("{} IMU topics: {}; choose with --topic NAME (repeatable: "
                                 "each topic one tag)",
                                 data.size(), TopicList(log, imu)));
  }
  return Status::Ok();
}

const char* TimeName(const LoadOptions& options) {
  return options.ros_time == LoadOptions::RosTime::kReceive ? "log time" : "header.stamp";
}

// Sample times strictly increasing (PlanTimeOrder): sorted with repeats after the first
// dropped, or refused (--time-order refuse). Counts in the notes.
Status OrderTimes(const RosLog& log, const LoadOptions& options, TopicData* d,
                  std::vector<std::string>* notes) {
  const TimeOrderPlan plan = PlanTimeOrder(d->t_ns);
  if (plan.in_order()) return Status::Ok();
  if (options.time_order == LoadOptions::TimeOrder::kRefuse) {
    const size_t i = plan.first_not_after;
    return MakeError(log.path, 0,
                     fmt::format("{} {}: message {} ({}): {} {} ns is not after the "
                                 "previous message's {} ns; expected increasing times "
                                 "(--time-order sort sorts them)",
                                 log.offset_name, d->offset[i], d->index[i], d->topic,
                                 TimeName(options), d->t_ns[i], d->t_ns[i - 1]));
  }
  Permute(plan.keep, &d->t_ns);
  Permute(plan.keep, &d->index);
  Permute(plan.keep, &d->offset);
  for (std::vector<double>& c : d->columns) Permute(plan.keep, &c);
  notes->push_back(
      fmt::format("{}: {} messages out of {} order, sorted; {} repeated {} dropped "
                  "(the first in the file kept) (--time-order sort)",
                  d->topic, plan.late, TimeName(options), plan.repeats, TimeName(options)));
  return Status::Ok();
}

std::string Matrix(const double* m) { return fmt::format("[{}]", fmt::join(m, m + 9, ", ")); }

// The message's covariances, which the session has no column for, as notes.
void CovarianceNotes(const TopicData& d, std::vector<std::string>* notes) {
  const char* names[3] = {"orientation_covariance [rad^2]",
                          "angular_velocity_covariance [(rad/s)^2]",
                          "linear_acceleration_covariance [(m/s^2)^2]"};
  for (int k = 0; k < 3; ++k) {
    if (k == 0 && d.with_orientation == 0) continue;
    notes->push_back(fmt::format(
        "{}: {} (row major, x y z) = {} {}", d.topic, names[k], Matrix(d.covariance[k]),
        d.covariance_changes[k] == 0 ? std::string("in every message")
                                     : fmt::format("in the first message; {} later messages differ",
                                                   d.covariance_changes[k])));
  }
}

Tag MakeTag(const TopicData& d, int sensor, int64_t t0_ns, bool orientation) {
  Tag tag;
  tag.sensor = sensor;
  tag.source_name = d.topic;
  tag.t_ns = d.t_ns;
  tag.t_s.reserve(d.t_ns.size());
  for (int64_t t : d.t_ns) tag.t_s.push_back(static_cast<double>(t - t0_ns) * 1e-9);
  tag.line.reserve(d.index.size());
  for (int64_t i : d.index) tag.line.push_back(static_cast<uint32_t>(i));
  for (int k = orientation ? 0 : 4; k < 10; ++k) {
    tag.quantities.push_back(Quantity{kColumns[k], kUnits[k], QuantityOrigin::kFile, d.columns[k]});
  }
  tag.counts.frames = tag.counts.fresh = static_cast<int64_t>(d.t_ns.size());
  return tag;
}

}  // namespace

namespace {

void AddLogNotes(const RosLog& log, const LoadOptions& options, Session* session) {
  InputDialect& in = session->input;
  in.notes.insert(in.notes.begin(),
                  fmt::format("{}: t_s = (t - t0) * 1e-9 s, t the message's {} [ns since the "
                              "Unix epoch], t0 = {} ns (the first sample read); line numbers are "
                              "1-based message indexes in the file",
                              log.format, TimeName(options), in.time_origin_ns));
  if (log.truncated_bytes > 0) {
    in.warnings.push_back(
        fmt::format("truncated file: the last {} bytes are an incomplete "
                    "record, skipped (--lenient)",
                    log.truncated_bytes));
  }
  for (const std::string& p : log.problems) {
    ++session->rejected_rows;
    if (session->rejected_reasons.size() < options.max_rejected_kept) {
      session->rejected_lines.push_back(log.message_count);
      session->rejected_reasons.push_back(p);
    }
  }
}

Result<Session> BuildSession(const RosLog& log, std::vector<TopicData> data,
                             const LoadOptions& options, Session session) {
  if (Status s = CheckTopics(log, options, data); !s.ok()) return s.error();
  if (!options.topics.empty()) {  // Tags in --topic order.
    std::vector<TopicData> ordered;
    for (const std::string& t : options.topics) {
      for (TopicData& d : data) {
        if (d.topic == t) ordered.push_back(std::move(d));
      }
    }
    data.swap(ordered);
  }
  std::vector<std::string> notes;
  int64_t t0_ns = std::numeric_limits<int64_t>::max();
  for (TopicData& d : data) {
    if (Status s = OrderTimes(log, options, &d, &notes); !s.ok()) return s.error();
    if (!d.t_ns.empty()) t0_ns = std::min(t0_ns, d.t_ns.front());
  }
  if (t0_ns == std::numeric_limits<int64_t>::max()) {
    return MakeError(log.path, 0, "no IMU message could be read (all rejected)");
  }
  session.path = log.path;
  session.columns = {"t_s", "sensor"};
  InputDialect& in = session.input;
  in.header_line = 0;
  in.time_source = TimeName(options);
  in.time_unit = "ns";
  in.time_integer = true;
  in.time_origin_ns = t0_ns;
  for (size_t k = 0; k < data.size(); ++k) {
    const TopicData& d = data[k];
    const int64_t n = static_cast<int64_t>(d.t_ns.size());
    const bool orientation = d.with_orientation > 0 && d.with_orientation == n;
    if (d.with_orientation > 0 && !orientation) {
      in.warnings.push_back(
          fmt::format("{}: {} of {} messages have an orientation: qw..qz left "
                      "out",
                      d.topic, d.with_orientation, n));
    }
    in.notes.push_back(fmt::format("sensor {} = {} ({} messages{})", k + 1, d.topic, n,
                                   orientation ? ", with orientation" : ""));
    CovarianceNotes(d, &in.notes);
    session.rows += n;
    session.tags.push_back(MakeTag(d, static_cast<int>(k) + 1, t0_ns, orientation));
    for (const Quantity& q : session.tags.back().quantities) {
      if (std::find(session.columns.begin(), session.columns.end(), q.name) ==
          session.columns.end()) {
        session.columns.push_back(q.name);
      }
    }
  }
  in.notes.insert(in.notes.end(), notes.begin(), notes.end());
  AddLogNotes(log, options, &session);
  session.rows += session.rejected_rows;
  return session;
}

Result<Session> ReadRosSession(const std::string& path, SessionFormat format,
                               const LoadOptions& options) {
  Session session;
  session.format = format;
  Collector collector(options, &session);
  const RosMessageVisitor visit = [&](const RosLog& log, const RosMessageView& m) {
    return collector.Visit(log, m);
  };
  RosLogReadOptions read;
  read.lenient = options.lenient;
  Result<RosLog> log = format == SessionFormat::kMcap      ? ReadMcap(path, read, visit)
                       : format == SessionFormat::kRosbag1 ? ReadRosbag1(path, read, visit)
                                                           : ReadRosbag2(path, read, visit);
  if (!log.ok()) return log.error();
  return BuildSession(log.value(), std::move(collector.topics()), options, std::move(session));
}

}  // namespace

Result<Session> LoadRosSession(const std::string& path, SessionFormat format,
                               const LoadOptions& options) {
  // The file is hashed on a second thread while it is read and decoded (a rosbag2 folder:
  // its metadata.yaml and storage files, RosbagDigest).
  Result<std::string> digest = std::string();
  Result<Session> session = MakeError(path, 0, "not loaded");
  RunBeside(
      [&] { digest = format == SessionFormat::kRosbag2 ? Rosbag2Digest(path) : Sha256File(path); },
      [&] { session = ReadRosSession(path, format, options); });
  if (!session.ok()) return session;
  if (!digest.ok()) return digest.error();
  session.value().sha256 = digest.value();
  return session;
}

}  // namespace metro::internal
