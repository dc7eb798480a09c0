#include "metro/io/session_stream.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <map>
#include <optional>

#include "core/parallel.hpp"
#include "io/csv_blocks.hpp"
#include "io/session_internal.hpp"
#include "io/stdin_input.hpp"
#include "metro/core/file.hpp"

namespace metro {

namespace {

Result<Session> StreamFile(const std::string& path, const LoadOptions& options,
                           const std::function<Status(Session& group)>& on_group,
                           size_t group_bytes);

// stdin, a FIFO or a device: copied once to a temporary file on disk (not in memory: the
// streaming mode's point), which is then streamed; the session and its errors name `name`.
Result<Session> StreamCopy(internal::StdinCopyOptions copy_options, const LoadOptions& options,
                           const std::function<Status(Session& group)>& on_group,
                           size_t group_bytes) {
  copy_options.try_memfd = false;
  auto copy = internal::CopyStdinToFile(copy_options);
  if (!copy.ok()) return copy.error();
  return internal::NamedAsStream(StreamFile(copy.value().path(), options, on_group, group_bytes),
                                 copy.value().path(), copy_options.display_name);
}

}  // namespace

Result<Session> StreamSession(const std::string& path, const LoadOptions& options,
                              const std::function<Status(Session& group)>& on_group,
                              size_t group_bytes) {
  if (internal::IsStdinPath(path)) {
    return StreamCopy(internal::StdinCopyOptions(), options, on_group, group_bytes);
  }
  struct stat st {};
  if (::stat(path.c_str(), &st) == 0 && !S_ISREG(st.st_mode) && !S_ISDIR(st.st_mode)) {
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) return MakeError(path, 0, std::string("cannot open: ") + std::strerror(errno));
    internal::StdinCopyOptions copy_options;
    copy_options.source_fd = fd;
    copy_options.display_name = path;
    Result<Session> session = StreamCopy(copy_options, options, on_group, group_bytes);
    ::close(fd);
    return session;
  }
  return StreamFile(path, options, on_group, group_bytes);
}

namespace {

Result<Session> StreamFile(const std::string& path, const LoadOptions& options,
                           const std::function<Status(Session& group)>& on_group,
                           size_t group_bytes) {
  std::string why;
  if (!options.IsValid(&why)) return MakeError(path, 0, "invalid load options: " + why);
  SessionFormat format = options.format;
  if (format == SessionFormat::kAuto) {
    auto detected = DetectSessionFormat(path);
    if (!detected.ok()) return detected.error();
    format = detected.value();
  }
  if (format == SessionFormat::kReceiver || format == SessionFormat::kULog ||
      format == SessionFormat::kImuTk || format == SessionFormat::kDataFlash) {
    return MakeError(path, 0,
                     fmt::format("{} input is not available in streaming mode (text sessions "
                                 "are: session.csv, euroc, raw, phyphox, sensor-logger); run "
                                 "without --stream",
                                 SessionFormatName(format)));
  }
  if (!options.topics.empty()) {
    return MakeError(path, 0, "--topic: topics are chosen in ULog input, not in streaming mode");
  }
  internal::MappedFile file;
  if (Status s = file.Open(path); !s.ok()) return s.error();
  if (file.size() == 0) {
    return MakeError(path, 0,
                     "empty file: expected a session.csv header line (t_s,...) followed by data "
                     "rows");
  }
  internal::HeaderLine header;
  auto plan = internal::PlanCsv(path, file, options, format, &header);
  if (!plan.ok()) return plan.error();
  // Euler angles per group, as LoadSession derives them; a quaternion off unit norm is
  // warned about once per tag, from the first group that shows it (its norms are that
  // group's, and the warning says so).
  std::map<int, std::string> euler_warnings;
  const auto derive = [&](Session& group) {
    if (options.derive_euler) {
      for (Tag& tag : group.tags) {
        std::string w = DeriveEulerIfAbsent(&tag);
        if (!w.empty() && euler_warnings.count(tag.sensor) == 0) {
          euler_warnings[tag.sensor] = fmt::format(
              "{} (in the group of rows from line {}, streaming mode)", w, tag.line.front());
        }
      }
    }
    return on_group(group);
  };
  Result<std::string> digest = std::string();
  std::optional<Result<Session>> session;
  internal::RunBeside([&] { digest = Sha256File(path); },
                      [&] {
                        session = internal::StreamGeneralCsv(path, file, header, plan.value(),
                                                             options, group_bytes, derive);
                      });
  if (const std::string changed = file.ChangedSinceOpen(); !changed.empty()) {
    return MakeError(path, 0, changed);
  }
  if (!session->ok()) return *std::move(session);
  if (!digest.ok()) return digest.error();
  session->value().sha256 = digest.value();
  for (auto& [sensor, w] : euler_warnings) {
    session->value().input.warnings.push_back(std::move(w));
  }
  return *std::move(session);
}

}  // namespace

}  // namespace metro
