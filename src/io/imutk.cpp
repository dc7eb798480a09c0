// imu_tk's text format: one file per sensor, `timestamp_s x y z` per line, whitespace
// separated (imu_tk's importAsciiData with TIMESTAMP_UNIT_SEC). Values are raw counts.
#include <fast_float/fast_float.h>
#include <fmt/format.h>

#include <cmath>
#include <new>

#include "core/parallel.hpp"
#include "io/session_internal.hpp"
#include "metro/core/file.hpp"

namespace metro {
namespace {

struct ImuTkFile {
  std::vector<double> t_s;
  std::vector<uint32_t> line;
  std::vector<double> xyz[3];
  int64_t rejected = 0;
  std::vector<int64_t> rejected_lines;
  std::vector<std::string> rejected_reasons;
};

bool IsSpace(char c) { return c == ' ' || c == '\t' || c == '\r'; }

Result<ImuTkFile> ReadImuTkFile(const std::string& path, const LoadOptions& options) {
  auto text_or = ReadFile(path, internal::kMaxRecordingBytes);
  if (!text_or.ok()) return text_or.error();
  const std::string& text = text_or.value();
  if (text.empty()) return MakeError(path, 0, "empty file: expected imu_tk lines 't x y z'");
  if (text.find('\0') != std::string::npos) {
    return MakeError(path, 0, "binary data (NUL bytes): expected imu_tk text lines 't x y z'");
  }
  ImuTkFile out;
  size_t pos = 0;
  int64_t line_number = 0;
  while (pos < text.size()) {
    size_t nl = text.find('\n', pos);
    if (nl == std::string::npos) nl = text.size();
    const char* p = text.data() + pos;
    const char* e = text.data() + nl;
    pos = nl + 1;
    ++line_number;
    while (p < e && IsSpace(*p)) ++p;
    if (p == e || *p == '#') continue;
    double v[4];
    std::string problem;
    for (int k = 0; k < 4 && problem.empty(); ++k) {
      while (p < e && IsSpace(*p)) ++p;
      const char* b = p;
      while (p < e && !IsSpace(*p)) ++p;
      if (b == p) {
        problem = fmt::format("expected 4 numbers 't x y z', found {}", k);
        break;
      }
      const char* nb = *b == '+' ? b + 1 : b;
      const auto r = fast_float::from_chars(nb, p, v[k]);
      if (r.ec != std::errc() || r.ptr != p || !std::isfinite(v[k])) {
        problem =
            fmt::format("field {}: expected a finite number, found '{}'", k + 1, std::string(b, p));
      }
    }
    while (problem.empty() && p < e && IsSpace(*p)) ++p;
    if (problem.empty() && p != e) problem = "expected 4 numbers 't x y z', found more";
    if (problem.empty() && !out.t_s.empty() && !(v[0] > out.t_s.back())) {
      problem = fmt::format("timestamp {} is not after the previous {} (line {})", v[0],
                            out.t_s.back(), out.line.back());
    }
    if (!problem.empty()) {
      if (!options.lenient) return MakeError(path, line_number, problem);
      ++out.rejected;
      if (out.rejected_lines.size() < options.max_rejected_kept) {
        out.rejected_lines.push_back(line_number);
        out.rejected_reasons.push_back(path + ": " + problem);
      }
      continue;
    }
    if (line_number > internal::kMaxLineNumber) {
      return internal::TooManyLinesError(path, line_number);
    }
    out.t_s.push_back(v[0]);
    out.line.push_back(static_cast<uint32_t>(line_number));
    for (int k = 0; k < 3; ++k) out.xyz[k].push_back(v[k + 1]);
  }
  if (out.t_s.empty()) return MakeError(path, 0, "no data lines: expected imu_tk lines 't x y z'");
  return out;
}

Result<Session> LoadImuTkOrThrow(const std::string& acc_path, const std::string& gyro_path,
                                 const LoadOptions& options) {
  Result<ImuTkFile> acc = MakeError("unset");
  Result<ImuTkFile> gyro = MakeError("unset");
  internal::RunBeside([&] { acc = ReadImuTkFile(acc_path, options); },
                      [&] { gyro = ReadImuTkFile(gyro_path, options); });
  if (!acc.ok()) return acc.error();
  if (!gyro.ok()) return gyro.error();
  const ImuTkFile& a = acc.value();
  const ImuTkFile& g = gyro.value();
  // imu_tk samples both sensors together: the timestamps must be the same.
  const size_t n = std::min(a.t_s.size(), g.t_s.size());
  for (size_t i = 0; i < n; ++i) {
    if (a.t_s[i] != g.t_s[i]) {
      return MakeError(gyro_path, g.line[i],
                       fmt::format("timestamp {} differs from the accelerometer's {} ({}:{}): "
                                   "imu_tk files must hold the same timestamps",
                                   g.t_s[i], a.t_s[i], acc_path, a.line[i]));
    }
  }
  if (a.t_s.size() != g.t_s.size()) {
    return MakeError(a.t_s.size() > n ? acc_path : gyro_path, 0,
                     fmt::format("{} samples in {} but {} in {}: imu_tk files must hold the "
                                 "same timestamps",
                                 a.t_s.size(), acc_path, g.t_s.size(), gyro_path));
  }
  Session session;
  session.path = acc_path + "+" + gyro_path;
  session.format = SessionFormat::kImuTk;
  session.rows = static_cast<int64_t>(n) + a.rejected + g.rejected;
  session.rejected_rows = a.rejected + g.rejected;
  for (const ImuTkFile* f : {&a, &g}) {
    session.rejected_lines.insert(session.rejected_lines.end(), f->rejected_lines.begin(),
                                  f->rejected_lines.end());
    session.rejected_reasons.insert(session.rejected_reasons.end(), f->rejected_reasons.begin(),
                                    f->rejected_reasons.end());
  }
  session.columns = {"t_s", "ax_lsb", "ay_lsb", "az_lsb", "gx_lsb", "gy_lsb", "gz_lsb"};
  Tag tag;
  tag.sensor = 1;
  tag.t_s = a.t_s;
  tag.line = a.line;
  const char* names[6] = {"ax_lsb", "ay_lsb", "az_lsb", "gx_lsb", "gy_lsb", "gz_lsb"};
  for (int k = 0; k < 6; ++k) {
    tag.quantities.push_back(
        Quantity{names[k], "LSB", QuantityOrigin::kFile, k < 3 ? a.xyz[k] : g.xyz[k - 3]});
  }
  tag.counts.frames = tag.counts.fresh = static_cast<int64_t>(n);
  session.tags.push_back(std::move(tag));
  auto acc_hash = Sha256File(acc_path);
  auto gyro_hash = Sha256File(gyro_path);
  if (!acc_hash.ok()) return acc_hash.error();
  if (!gyro_hash.ok()) return gyro_hash.error();
  session.sha256 = acc_hash.value() + "+" + gyro_hash.value();
  return session;
}

}  // namespace

Result<Session> LoadImuTk(const std::string& acc_path, const std::string& gyro_path,
                          const LoadOptions& options) {
  try {
    return LoadImuTkOrThrow(acc_path, gyro_path, options);
  } catch (const std::bad_alloc&) {
    return internal::OutOfMemoryError(acc_path + "+" + gyro_path);
  }
}

}  // namespace metro
