// characterize convert INPUT... -o session.csv [--format auto|csv|receiver|euroc|raw|phyphox|
//   sensorlogger|ulog] [--imutk]: one session to canonical session.csv, several files of one
//   recording joined on time, or imu_tk's two files. --format is the flag every command that
//   loads a session has (load_cli.hpp); --from FORMAT is its older spelling here (--from imutk:
//   --imutk).
#include <fmt/format.h>

#include "commands.hpp"
#include "load_cli.hpp"
#include "metro/core/file.hpp"
#include "metro/io/session_io.hpp"
#include "metro/io/session_join.hpp"
#include "output.hpp"

namespace metro::apps {
namespace {

struct ConvertOptions {
  std::vector<std::string> inputs;
  std::string from;    // --from FORMAT, the older spelling of --format (and of --imutk).
  bool imutk = false;  // --imutk: the inputs are imu_tk's two files, ACC GYRO.
  std::string output;
  LoadCliOptions load;  // --format and the other load flags.
};

int RunConvert(const ConvertOptions& o) {
  LoadCliOptions flags = o.load;
  if (!o.from.empty() && o.from != "imutk") flags.format = o.from;
  const bool imutk = o.imutk || o.from == "imutk";
  LoadOptions load;
  if (Status s = MakeLoadOptions(flags, &load); !s.ok()) {
    return PrintErrorExit(s.error());
  }
  if (Status s = CheckStdinInputs(o.inputs, imutk); !s.ok()) {
    return PrintErrorExit(s.error());
  }
  std::vector<NamedPath> inputs = {{"--columns-file", o.load.columns_file}};
  for (const std::string& input : o.inputs) inputs.push_back({"INPUT", input});
  if (Status s = CheckOutputs({{"-o", o.output}}, inputs); !s.ok()) {
    return PrintErrorExit(s.error());
  }
  Result<Session> session = MakeError("no input");
  std::string join_comments;
  if (imutk) {
    if (o.inputs.size() != 2) {
      return PrintErrorExit(MakeError(std::string(o.imutk ? "--imutk" : "--from imutk") +
                                      " takes two inputs: ACC GYRO"));
    }
    session = LoadImuTk(o.inputs[0], o.inputs[1], load);
  } else if (o.inputs.size() == 1) {
    session = LoadSession(o.inputs[0], load);
  } else {
    // The per-sensor files of one recording, joined on time (docs/formats.md).
    std::vector<Session> parts;
    for (const std::string& input : o.inputs) {
      auto part = LoadSession(input, load);
      if (!part.ok()) {
        return PrintErrorExit(part.error());
      }
      parts.push_back(std::move(part).value());
    }
    JoinSummary summary;
    session = JoinSessionsOnTime(parts, &summary);
    for (size_t i = 0; session.ok() && i < parts.size(); ++i) {
      // One line, in the note and in the file's comment: the file name is data (escaped).
      const std::string line =
          fmt::format("joined {}: {} samples, {} in no joined row",
                      EscapeControlChars(parts[i].path), summary.samples[i], summary.unmatched[i]);
      join_comments += "# " + line + "\n";
      Note(line + "\n");
    }
  }
  if (!session.ok()) {
    return PrintErrorExit(session.error());
  }
  const Session& s = session.value();
  // Provenance and the frame counts, which session.csv rows cannot carry, as comments (one
  // line each: a newline in the input's name must not start a data row).
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
  text += join_comments;
  text += FormatSessionCsv(s, true);
  if (Status w = WriteOutput(o.output, text); !w.ok()) {
    return PrintErrorExit(w.error());
  }
  int64_t observations = 0;
  for (const Tag& t : s.tags) observations += static_cast<int64_t>(t.size());
  Note(fmt::format("wrote {}: {} tags, {} observations\n", IsStdio(o.output) ? "stdout" : o.output,
                   s.tags.size(), observations));
  return kExitOk;
}

}  // namespace

void AddConvertCommand(CLI::App& app, int* exit_code) {
  auto o = std::make_shared<ConvertOptions>();
  CLI::App* sub = app.add_subcommand(
      "convert",
      "turn any readable session (receiver capture, EuRoC, raw prints, phyphox, Sensor Logger, PX4 "
      "ULog, MCAP, ROS 1 and ROS 2 bags, imu_tk's two files) into canonical session.csv; several "
      "files are joined on time");
  sub->add_option("inputs", o->inputs,
                  "INPUT, several files of one recording (joined on time), or ACC GYRO with "
                  "--imutk; - reads stdin")
      ->required()
      ->check(ExistingFileOrStdin());
  sub->add_option("-o,--output", o->output, "session.csv to write (- for stdout)")->required();
  // The load flags, --format among them, as every command that loads a session has them.
  AddLoadCliOptions(sub, &o->load);
  CLI::Option* format = sub->get_option("--format");
  CLI::Option* imutk =
      sub->add_flag("--imutk", o->imutk, "the inputs are imu_tk's two files: ACC GYRO")
          ->excludes(format);
  sub->add_option("--from", o->from, "the older spelling of --format (--from imutk: --imutk)")
      ->check(CLI::IsMember({"auto", "receiver", "csv", "imutk", "euroc", "raw", "phyphox",
                             "sensorlogger", "phone", "ulog"}))
      ->excludes(format)
      ->excludes(imutk);
  sub->callback([o, exit_code] { *exit_code = RunConvert(*o); });
}

}  // namespace metro::apps
