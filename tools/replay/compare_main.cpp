// hystloop-replay-compare: compares the commands of a replayed compensator with the recorded ones.
//
//   hystloop-replay-compare EXPECTED.lcmlog ACTUAL.lcmlog [--inputs INPUTS.lcmlog]
//                           [--tolerance-V V] [--tolerance-m M] [--rig HX_]
//
// Takes the command_block_t blocks apart into ticks and matches them by tick, over the ticks
// the original commanded, every axis the blocks carry (each with its own report); compares u_ff_V, y_ref_m, mode,
// params_version (exact by default: bitwise equal doubles). Prints the first divergence (tick, field, expected, got)
// and a summary. Exit 0: equal; 1: diverged, nothing compared, or the replay lost samples in transport with no
// divergence before the first loss (the verdict line tells which); 2: bad arguments, or a log that cannot be read or
// holds no command (tools/replay-check reads 1 as a verdict on the compensator, so these must not exit 1).

#include <CLI/CLI.hpp>

#include <algorithm>
#include <cstdio>
#include <exception>
#include <optional>
#include <set>
#include <string>

#include "core/cli.hpp"
#include "command_comparison.hpp"
#include "core/errors.hpp"
#include "models/axis_coupling.hpp"

namespace {

// read() with whatever it throws turned into a ParameterError naming `argument` ("expected: run.lcmlog: no such
// log file"), which run_tool exits 2 on: a log that cannot be read is refused input, not a divergence.
template <class Read>
auto read_argument(const char* argument, Read&& read) {
  try {
    return read();
  } catch (const hystloop::ParameterError&) {
    throw;
  } catch (const std::exception& e) {
    throw hystloop::ParameterError(argument, e.what());
  }
}

int run_compare(int argc, char** argv) {
  CLI::App app{"Compares a replayed compensator's commands with a recorded log's (tools/replay-check)."};
  std::string expected_log, actual_log, inputs_log, rig = std::string(hystloop::kDefaultRigPrefix);
  hystloop::replay::CompareTolerance tolerance;
  app.add_option("expected", expected_log, "Recorded log (the original compensator's HX_COMMAND)")->required();
  app.add_option("actual", actual_log, "Log of the replayed compensator's HX_COMMAND")->required();
  app.add_option("--inputs", inputs_log,
                 "The inputs log that was played (its samples tell a transport loss from a missing command)");
  app.add_option("--tolerance-V", tolerance.voltage_V, "Accept |expected - got| up to this on u_ff_V [V] (0: bitwise)")
      ->capture_default_str();
  app.add_option("--tolerance-m", tolerance.position_m,
                 "Accept |expected - got| up to this on y_ref_m [m] (0: bitwise)")
      ->capture_default_str();
  app.add_option("--rig", rig, "Channel prefix of the rig")->capture_default_str();
  if (const auto exit_code = hystloop::parse_cli(app, argc, argv)) return *exit_code;

  tolerance.validate();
  const hystloop::ChannelNames channels(rig);
  std::optional<std::set<std::int64_t>> played;
  if (!inputs_log.empty()) {
    played = read_argument("--inputs", [&] { return hystloop::replay::read_sample_seqs(inputs_log, channels); });
  }
  // Every axis the recorded blocks carry, each compared on its own (a one-axis log: x, as always).
  int axes = 1;
  int exit_code = hystloop::kExitOk;
  for (int axis = 0; axis < axes; ++axis) {
    const auto expected =
        read_argument("expected", [&] { return hystloop::replay::read_commands(expected_log, channels, axis); });
    const auto actual =
        read_argument("actual", [&] { return hystloop::replay::read_commands(actual_log, channels, axis); });
    axes = std::max(expected.axes, 1);
    if (expected.by_seq.empty()) {
      throw hystloop::ParameterError("expected", expected_log + " holds no " + channels.command + " command");
    }
    if (axes > 1) std::printf("axis %s:\n", std::string(hystloop::axis_name(axis)).c_str());
    if (actual.axes != expected.axes) {
      std::printf("verdict: the replay's blocks carry %d axes, the log's %d\n", actual.axes, expected.axes);
      return 1;
    }
    const auto report = hystloop::replay::compare_commands(expected, actual, played ? &*played : nullptr, tolerance);
    if (expected.duplicates + expected.undecodable + actual.duplicates + actual.undecodable > 0) {
      std::printf(
          "note: ignored: expected %llu repeated ticks / %llu undecodable blocks, actual %llu repeated ticks / %llu "
          "undecodable blocks\n",
          static_cast<unsigned long long>(expected.duplicates), static_cast<unsigned long long>(expected.undecodable),
          static_cast<unsigned long long>(actual.duplicates), static_cast<unsigned long long>(actual.undecodable));
    }
    std::fputs(hystloop::replay::format_report(report, tolerance).c_str(), stdout);
    if (exit_code == hystloop::kExitOk) exit_code = report.exit_code();
  }
  return exit_code;
}

}  // namespace

int main(int argc, char** argv) {
  return hystloop::run_tool("hystloop-replay-compare", [&] { return run_compare(argc, argv); });
}
