// characterize convert INPUT... -o session.csv [--format auto|csv|receiver|euroc|raw|phyphox|
//   sensorlogger|ulog] [--imutk]: one session to canonical session.csv, several files of one
//   recording joined on time, or imu_tk's two files. --format is the flag every command that
//   loads a session has (load_cli.hpp); --from FORMAT is its older spelling here (--from imutk:
//   --imutk).
#include "convert_command.hpp"

#include <fmt/format.h>

#include "load_cli.hpp"
#include "metro/core/file.hpp"
#include "metro/io/session_io.hpp"
#include "metro/io/session_join.hpp"
#include "output.hpp"

namespace metro::apps {
namespace {

// The per-sensor files of one recording, joined on time (docs/formats.md); one line per file,
// in the note and in the output's comments (`comments`): the file name is data (escaped).
Result<Session> LoadJoined(const std::vector<std::string>& files, const LoadOptions& load,
                           std::string* comments) {
  std::vector<Session> parts;
  for (const std::string& input : files) {
    Result<Session> part = LoadSession(input, load);
    if (!part.ok()) return part.error();
    parts.push_back(std::move(part).value());
  }
  JoinSummary summary;
  Result<Session> session = JoinSessionsOnTime(parts, &summary);
  for (size_t i = 0; session.ok() && i < parts.size(); ++i) {
    const std::string line =
        fmt::format("joined {}: {} samples, {} in no joined row", EscapeControlChars(parts[i].path),
                    summary.samples[i], summary.unmatched[i]);
    *comments += "# " + line + "\n";
    Note(line + "\n");
  }
  return session;
}

// The inputs as one session: imu_tk's two files, one file, or several joined on time.
Result<Session> LoadConvertInputs(const ConvertOptions& o, const LoadOptions& load, bool imutk,
                                  std::string* comments) {
  if (imutk) {
    if (o.inputs.size() != 2) {
      return MakeError(std::string(o.imutk ? "--imutk" : "--from imutk") +
                       " takes two inputs: ACC GYRO");
    }
    return LoadImuTk(o.inputs[0], o.inputs[1], load);
  }
  if (o.inputs.size() == 1) return LoadSession(o.inputs[0], load);
  return LoadJoined(o.inputs, load, comments);
}

// session.csv with the provenance and the frame counts, which its rows cannot carry, as
// comments (one line each: a newline in the input's name must not start a data row).
std::string ConvertedText(const Session& s, const std::string& join_comments) {
  std::string text = fmt::format("# metro convert: {} ({}, sha256 {})\n",
                                 EscapeControlChars(s.path), SessionFormatName(s.format), s.sha256);
  if (s.format == SessionFormat::kReceiver) {
    text += fmt::format("# frame_period_s {}\n", s.frame_period_s);
    for (const Tag& t : s.tags) {
      text += fmt::format("# sensor {}: frames {} fresh {} stale {} never {}\n", t.sensor,
                          t.counts.frames, t.counts.fresh, t.counts.stale, t.counts.never);
    }
  }
  if (s.rejected_rows > 0) text += fmt::format("# rejected_rows {}\n", s.rejected_rows);
  return text + join_comments + FormatSessionCsv(s, true);
}

}  // namespace

int RunConvert(const ConvertOptions& o) {
  LoadCliOptions flags = o.load;
  if (!o.from.empty() && o.from != "imutk") flags.format = o.from;
  const bool imutk = o.imutk || o.from == "imutk";
  LoadOptions load;
  if (Status s = MakeLoadOptions(flags, &load); !s.ok()) return PrintErrorExit(s.error());
  if (Status s = CheckStdinInputs(o.inputs, imutk); !s.ok()) return PrintErrorExit(s.error());
  std::vector<NamedPath> inputs = {{"--columns-file", o.load.columns_file}};
  for (const std::string& input : o.inputs) inputs.push_back({"INPUT", input});
  if (Status s = CheckOutputs({{"-o", o.output}}, inputs); !s.ok()) {
    return PrintErrorExit(s.error());
  }
  std::string join_comments;
  Result<Session> session = LoadConvertInputs(o, load, imutk, &join_comments);
  if (!session.ok()) return PrintErrorExit(session.error());
  const Session& s = session.value();
  if (Status w = WriteOutput(o.output, ConvertedText(s, join_comments)); !w.ok()) {
    return PrintErrorExit(w.error());
  }
  int64_t observations = 0;
  for (const Tag& t : s.tags) observations += static_cast<int64_t>(t.size());
  Note(fmt::format("wrote {}: {} tags, {} observations\n", IsStdio(o.output) ? "stdout" : o.output,
                   s.tags.size(), observations));
  return kExitOk;
}

}  // namespace metro::apps
