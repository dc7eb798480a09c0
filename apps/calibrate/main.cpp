// calibrate: accelerometer and gyroscope calibration with the uncertainty of every constant.
// A dispatch table: each subcommand's flags are bound to its options struct in its
// *_flags.hpp, the work is done by its Run function (*_command.hpp) and the metro library
// (metro/calibration/). This is the program's one translation unit with CLI11 (issue #39).
#include <cstdio>
#include <memory>
#include <new>

#include "apply_flags.hpp"
#include "blob_flags.hpp"
#include "commands.hpp"
#include "common_flags.hpp"
#include "export_flags.hpp"
#include "fit_flags.hpp"
#include "import_flags.hpp"
#include "inspect_flags.hpp"
#include "push_flags.hpp"
#include "registry_flags.hpp"
#include "report_flags.hpp"
#include "station_flags.hpp"

int main(int argc, char** argv) {
  // SIGINT/SIGTERM remove the temporaries of outputs being written; SIGXFSZ is ignored.
  metro::InstallInterruptCleanup();
  namespace app_ns = metro::calibrate_app;
  CLI::App app{"metro calibrate: IMU calibration (bias, scale, misalignment) with uncertainties"};
  app.require_subcommand(1);
  int exit_code = app_ns::kExitOk;
  app_ns::AddFitCommand(app, &exit_code);
  app_ns::AddApplyCommand(app, &exit_code);
  app_ns::AddReportCommand(app, &exit_code);
  app_ns::AddBlobCommand(app, &exit_code);
  app_ns::AddInspectCommand(app, &exit_code);
  app_ns::AddPushCommand(app, &exit_code);
  app_ns::AddRegistryCommand(app, &exit_code);
  app_ns::AddExportCommand(app, &exit_code);
  app_ns::AddImportCommand(app, &exit_code);
  app_ns::AddStationCommand(app, &exit_code);
  metro::apps::AddVersionFlag(app, "calibrate");
  metro::apps::AddQuietFlag(app);  // On the app and every subcommand (docs/unix.md).
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return metro::apps::FinishStdout(code == 0 ? 0 : app_ns::kExitUsage);
  } catch (const std::bad_alloc&) {
    // The loaders turn this into an error naming the file; anything else that runs out.
    std::fputs("error: out of memory\n", stderr);
    return app_ns::kExitFailed;
  }
  return metro::apps::FinishStdout(exit_code);
}
