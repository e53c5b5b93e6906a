// hystloop-export: a recorded run's LCM log channels as MATLAB .mat and HDF5 files.
//
//   hystloop-export LOG... [--mat FILE] [--hdf5 FILE] [--channel NAME]... [--from S] [--to S]
//                   [--config FILE]... [--rig PREFIX] [--mat-version 5|7.3] [--quiet]
//
// One struct (.mat) or group (HDF5) per channel, one column per decoded field, with units,
// integer-code legends and the run's configuration (docs/EXPORT.md).

#include <CLI/CLI.hpp>

#include <cstdio>
#include <map>
#include <string>

#include "lcm/rig_auth.hpp"
#include "core/cli.hpp"
#include "core/errors.hpp"
#include "export_run.hpp"

namespace {

using namespace hystloop;
using namespace hystloop::exporter;

constexpr const char* kExitCodes =
    "Exit status: 0 written; 1 a log could not be read, holds no channel of the rig, or an output could not be "
    "written (a half-written output is removed); 2 bad arguments: an unknown option, no --mat/--hdf5, --from not "
    "before --to, a --channel not in the log, a --config that is not a readable YAML file, a bad --rig.";

int export_main(int argc, char** argv) {
  ExportOptions o;
  CLI::App app{
      "hystloop-export: the channels of recorded LCM event logs as a MATLAB .mat file and/or an HDF5 file: one "
      "struct/group per channel, one column per field (per tick for HX_SENSOR and HX_COMMAND, as hystloop-report's "
      "CSV), with units, the meaning of integer codes and the run's configuration (docs/EXPORT.md)"};
  app.footer(kExitCodes);
  app.add_option("logs", o.logs, "LCM event log file(s); rotated files in recording order")
      ->required()
      ->check(CLI::ExistingFile);
  app.add_option("--mat", o.mat, "Write this MATLAB .mat file (replaced if it exists)");
  app.add_option("--hdf5", o.hdf5, "Write this HDF5 file (replaced if it exists)");
  app.add_option("--channel", o.channels,
                 "Export this channel, as logged (HX_SENSOR) or by suffix (SENSOR); repeatable. Default: every "
                 "channel of the rig's prefix in the log");
  app.add_option("--from", o.from_s, "Only rows from this time on [s after the first sensor tick]");
  app.add_option("--to", o.to_s, "Only rows up to this time [s after the first sensor tick]");
  app.add_option("--config", o.configs,
                 "A YAML configuration file of the run, stored verbatim (repeatable), e.g. deploy/config/*.yaml");
  app.add_option("--rig", o.rig, "Channel prefix of the rig")->capture_default_str();
  std::string key_file;
  app.add_option("--key-file", key_file,
                 "The rig key (auth.key_file of the services): verify the signed channels' messages and leave out "
                 "(and count, in the warnings) those whose signature fails, as the rig refused them");
  std::string mat_version = "5";
  app.add_option("--mat-version", mat_version,
                 "MAT file level: 5 (compressed, MATLAB's -v7 and scipy.io.loadmat) or 7.3 (HDF5-based, for "
                 "variables over 2 GB)")
      ->check(CLI::IsMember({"5", "7.3"}))
      ->capture_default_str();
  app.add_flag("--quiet", o.quiet, "No progress on stderr and no summary on stdout (warnings and errors still)");
  if (const auto exit_code = parse_cli(app, argc, argv)) return *exit_code;
  o.mat_version = mat_version == "7.3" ? MatVersion::kV73 : MatVersion::kV5;
  // The log's readers (report::for_each_event) verify with the process's key.
  if (!key_file.empty()) set_process_rig_auth(rig_auth_from_key_file(key_file, "--key-file"));
  return run_export(o, stderr, stdout);
}

}  // namespace

int main(int argc, char** argv) {
  return hystloop::run_tool("hystloop-export", [&] { return export_main(argc, argv); });
}
