// ROS 2 bag folders (metro/io/ros_log.hpp): metadata.yaml names the storage plugin and the
// files; sqlite3 files are read with libsqlite3 (rosbag2_storage_default_plugins' schema:
// topics(id, name, type, serialization_format, ...), messages(id, topic_id, timestamp,
// data)), MCAP files with the MCAP reader. Connections of the same topic and type in
// several files are one.
#include <fmt/format.h>
#include <sqlite3.h>
#include <sys/stat.h>
#include <unistd.h>

#include <fstream>
#include <memory>
#include <unordered_map>

#include "io/ros_log_internal.hpp"
#include "metro/core/file.hpp"
#include "metro/io/ros_log.hpp"

namespace metro {
namespace {

struct Bag2Files {
  std::string metadata;  // "" for a .db3 named alone.
  std::string storage;   // "sqlite3" or "mcap".
  std::vector<std::string> files;
};

bool IsDirectory(const std::string& path) {
  struct stat st {};
  return ::stat(path.c_str(), &st) == 0 && S_ISDIR(st.st_mode);
}

std::string Trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\r' || s.back() == '\t'))
    s.remove_suffix(1);
  if (s.size() >= 2 && (s.front() == '"' || s.front() == '\'') && s.back() == s.front()) {
    s = s.substr(1, s.size() - 2);
  }
  return std::string(s);
}

// metadata.yaml's storage_identifier and relative_file_paths (block or flow list), read
// line by line: rosbag2 writes both as plain scalars under rosbag2_bagfile_information.
Status ParseMetadata(const std::string& yaml_path, const std::string& text, Bag2Files* out) {
  std::vector<std::string> lines;
  for (size_t at = 0; at <= text.size();) {
    size_t nl = text.find('\n', at);
    if (nl == std::string::npos) nl = text.size();
    lines.push_back(text.substr(at, nl - at));
    at = nl + 1;
  }
  int64_t files_line = 0;
  for (size_t i = 0; i < lines.size(); ++i) {
    const std::string t = Trim(lines[i]);
    if (t.rfind("storage_identifier:", 0) == 0) out->storage = Trim(t.substr(19));
    if (t.rfind("relative_file_paths:", 0) != 0) continue;
    files_line = static_cast<int64_t>(i) + 1;
    std::string rest = Trim(t.substr(20));
    if (!rest.empty() && rest.front() == '[') {  // Flow: [a.db3, b.db3]
      rest = rest.substr(1, rest.find(']') == std::string::npos ? 0 : rest.find(']') - 1);
      for (size_t at = 0; at <= rest.size();) {
        size_t comma = rest.find(',', at);
        if (comma == std::string::npos) comma = rest.size();
        if (std::string f = Trim(rest.substr(at, comma - at)); !f.empty()) out->files.push_back(f);
        at = comma + 1;
      }
      continue;
    }
    for (size_t j = i + 1; j < lines.size(); ++j) {
      const std::string item = Trim(lines[j]);
      if (item.empty() || item[0] != '-') break;
      out->files.push_back(Trim(item.substr(1)));
    }
  }
  if (out->storage != "sqlite3" && out->storage != "mcap") {
    return MakeError(
        yaml_path, 0,
        fmt::format("storage_identifier \"{}\": expected sqlite3 or mcap", out->storage));
  }
  if (out->files.empty()) {
    return MakeError(yaml_path, files_line,
                     "no relative_file_paths entries; expected the bag's storage files "
                     "(\"- name.db3\" lines)");
  }
  return Status::Ok();
}

Result<Bag2Files> FindFiles(const std::string& path) {
  Bag2Files out;
  std::string dir;
  if (IsDirectory(path)) {
    dir = path;
    out.metadata = path + "/metadata.yaml";
  } else if (path.size() >= 13 && path.compare(path.size() - 13, 13, "metadata.yaml") == 0) {
    out.metadata = path;
    const size_t slash = path.rfind('/');
    dir = slash == std::string::npos ? "." : path.substr(0, slash);
  } else {
    out.storage = "sqlite3";
    out.files.push_back(path);
    return out;
  }
  auto text = ReadFile(out.metadata);
  if (!text.ok()) return text.error();
  if (Status s = ParseMetadata(out.metadata, text.value(), &out); !s.ok()) return s.error();
  for (std::string& f : out.files) f = dir + "/" + f;
  return out;
}

// The outer log's connection for (topic, type, encoding), added when new.
size_t Connection(RosLog* log, const std::string& topic, const std::string& type,
                  const std::string& encoding) {
  for (size_t i = 0; i < log->connections.size(); ++i) {
    const RosConnection& c = log->connections[i];
    if (c.topic == topic && c.type == type && c.encoding == encoding) return i;
  }
  RosConnection c;
  c.topic = topic;
  c.type = type;
  c.encoding = encoding;
  log->connections.push_back(std::move(c));
  return log->connections.size() - 1;
}

using Db = std::unique_ptr<sqlite3, decltype(&sqlite3_close)>;
using Stmt = std::unique_ptr<sqlite3_stmt, decltype(&sqlite3_finalize)>;

std::string Text(sqlite3_stmt* s, int col) {
  const unsigned char* t = sqlite3_column_text(s, col);
  return t == nullptr ? "" : reinterpret_cast<const char*>(t);
}

Result<Stmt> Prepare(sqlite3* db, const std::string& file, const char* sql) {
  sqlite3_stmt* raw = nullptr;
  if (sqlite3_prepare_v2(db, sql, -1, &raw, nullptr) != SQLITE_OK) {
    return MakeError(file, 0,
                     fmt::format("{}; expected rosbag2's sqlite3 schema (tables topics(id, name, "
                                 "type, serialization_format) and messages(id, topic_id, "
                                 "timestamp, data))",
                                 sqlite3_errmsg(db)));
  }
  return Stmt(raw, &sqlite3_finalize);
}

// The topics table: topic_id -> outer connection index.
Result<std::unordered_map<int64_t, size_t>> ReadTopics(sqlite3* db, const std::string& file,
                                                       RosLog* log) {
  auto stmt = Prepare(db, file, "SELECT id, name, type, serialization_format FROM topics");
  if (!stmt.ok()) return stmt.error();
  std::unordered_map<int64_t, size_t> out;
  int rc = 0;
  while ((rc = sqlite3_step(stmt.value().get())) == SQLITE_ROW) {
    sqlite3_stmt* s = stmt.value().get();
    out[sqlite3_column_int64(s, 0)] = Connection(log, Text(s, 1), Text(s, 2), Text(s, 3));
  }
  if (rc != SQLITE_DONE) return MakeError(file, 0, sqlite3_errmsg(db));
  return out;
}

Status ReadDb3(const std::string& file, RosLog* log, const RosMessageVisitor& visit) {
  sqlite3* raw = nullptr;
  const int open_rc = sqlite3_open_v2(file.c_str(), &raw, SQLITE_OPEN_READONLY, nullptr);
  Db db(raw, &sqlite3_close);
  if (open_rc != SQLITE_OK) {
    return MakeError(file, 0, fmt::format("cannot open as SQLite: {}", sqlite3_errstr(open_rc)));
  }
  auto topics = ReadTopics(db.get(), file, log);
  if (!topics.ok()) return topics.error();
  auto stmt =
      Prepare(db.get(), file, "SELECT id, topic_id, timestamp, data FROM messages ORDER BY id");
  if (!stmt.ok()) return stmt.error();
  log->offset_name = file + ": messages row id";
  sqlite3_stmt* s = stmt.value().get();
  int rc = 0;
  while ((rc = sqlite3_step(s)) == SQLITE_ROW) {
    const int64_t id = sqlite3_column_int64(s, 0);
    auto it = topics.value().find(sqlite3_column_int64(s, 1));
    if (it == topics.value().end()) {
      return MakeError(file, 0,
                       fmt::format("messages row id {}: topic_id {} is not in the topics "
                                   "table; expected one of its ids",
                                   id, sqlite3_column_int64(s, 1)));
    }
    const int64_t t_ns = sqlite3_column_int64(s, 2);
    internal::CountRosMessage(log, it->second, t_ns);
    if (!visit) continue;
    const void* blob = sqlite3_column_blob(s, 3);
    RosMessageView m;
    m.connection = it->second;
    m.log_time_ns = t_ns;
    m.data = std::string_view(static_cast<const char*>(blob),
                              static_cast<size_t>(sqlite3_column_bytes(s, 3)));
    m.record_offset = static_cast<uint64_t>(id);
    m.index = log->message_count;
    if (Status st = visit(*log, m); !st.ok()) return st;
  }
  if (rc != SQLITE_DONE) return MakeError(file, 0, sqlite3_errmsg(db.get()));
  return Status::Ok();
}

// One MCAP storage file, its connections and messages merged into `log`.
Status ReadMcapStorage(const std::string& file, const RosLogReadOptions& options, RosLog* log,
                       const RosMessageVisitor& visit) {
  log->offset_name = file + ": byte offset";
  std::vector<size_t> outer;  // Inner connection index -> outer.
  const RosMessageVisitor inner = [&](const RosLog& in, const RosMessageView& m) {
    while (outer.size() < in.connections.size()) {
      const RosConnection& c = in.connections[outer.size()];
      outer.push_back(Connection(log, c.topic, c.type, c.encoding));
    }
    RosMessageView o = m;
    o.connection = outer[m.connection];
    internal::CountRosMessage(log, o.connection, m.log_time_ns);
    o.index = log->message_count;
    return visit ? visit(*log, o) : Status::Ok();
  };
  auto in = ReadMcap(file, options, inner);
  if (!in.ok()) return in.error();
  for (const RosConnection& c : in.value().connections) {
    Connection(log, c.topic, c.type, c.encoding);  // Topics without messages listed too.
  }
  for (const auto& [name, n] : in.value().chunk_compressions) {
    for (int64_t k = 0; k < n; ++k) internal::CountRosChunk(log, name);
  }
  log->has_summary = log->has_summary || in.value().has_summary;
  log->truncated_bytes += in.value().truncated_bytes;
  log->problems.insert(log->problems.end(), in.value().problems.begin(), in.value().problems.end());
  return Status::Ok();
}

}  // namespace

bool IsRosbag2Path(const std::string& path) {
  if (IsDirectory(path)) return ::access((path + "/metadata.yaml").c_str(), R_OK) == 0;
  if (path.size() >= 13 && path.compare(path.size() - 13, 13, "metadata.yaml") == 0) return true;
  // Only a regular file is peeked at: opening a FIFO would take the bytes (or block) that the
  // loader is to read.
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0 || !S_ISREG(st.st_mode)) return false;
  std::ifstream in(path, std::ios::binary);
  char head[16] = {};
  return in.read(head, 16) &&
         std::string_view(head, 16) == std::string_view("SQLite format 3\0", 16);
}

Result<RosLog> ReadRosbag2(const std::string& path, const RosLogReadOptions& options,
                           const RosMessageVisitor& visit) {
  auto files = FindFiles(path);
  if (!files.ok()) return files.error();
  RosLog log;
  log.path = path;
  log.format = "ROS 2 bag (" + files.value().storage + ")";
  for (const std::string& f : files.value().files) {
    Status s = files.value().storage == "mcap" ? ReadMcapStorage(f, options, &log, visit)
                                               : ReadDb3(f, &log, visit);
    if (!s.ok()) return s.error();
  }
  return log;
}

namespace internal {

Result<std::string> Rosbag2Digest(const std::string& path) {
  auto files = FindFiles(path);
  if (!files.ok()) return files.error();
  std::vector<std::string> all = files.value().files;
  if (!files.value().metadata.empty()) all.insert(all.begin(), files.value().metadata);
  std::string out;
  for (const std::string& f : all) {
    auto d = Sha256File(f);
    if (!d.ok()) return d.error();
    out += (out.empty() ? "" : "+") + d.value();
  }
  return out;
}

}  // namespace internal
}  // namespace metro
