// hystloop-replay-filter: prepares logs for tools/replay-check.
//
//   hystloop-replay-filter inputs LOG OUT [--rig HX_] [--only-answered] [--compensator-process NAME]
//       OUT = the recorded compensator's inputs (SENSOR, TRAJECTORY, PARAMS, CONTROL) from the
//       sensor block holding the first sample it answered (the lowest sample_seq of its command
//       blocks) on, to play into a fresh compensator with lcm-logplayer.
//   hystloop-replay-filter alter LOG OUT (--seq N | --nth K) [--delta-V D]
//       OUT = LOG with the command for tick N (or the K-th tick commanded in the log) changed
//       (u_ff_V + D, default: 1 ulp flipped), to prove that a replay notices.
// Exit 0 on success, 1 when a log cannot be read or written (or holds no command), 2 on bad
// arguments. tools/replay-check stops on any non-zero exit.

#include <CLI/CLI.hpp>

#include <cstdio>
#include <optional>
#include <string>

#include "core/cli.hpp"
#include "core/errors.hpp"
#include "command_alteration.hpp"
#include "replay_inputs.hpp"

namespace {

int run_filter(int argc, char** argv) {
  CLI::App app{"Prepares LCM event logs for a replay regression (tools/replay-check)."};
  app.require_subcommand(1);
  std::string log, out, rig = std::string(hystloop::kDefaultRigPrefix);
  app.add_option("--rig", rig, "Channel prefix of the rig")->capture_default_str();

  hystloop::replay::ReplayInputOptions input_options;
  CLI::App* inputs =
      app.add_subcommand("inputs", "Write the recorded compensator's inputs, from its first answered sample");
  inputs->add_option("log", log, "Recorded LCM event log")->required();
  inputs->add_option("out", out, "Inputs-only log to write")->required();
  inputs->add_flag("--only-answered", input_options.only_answered,
                   "Also leave out sensor blocks the recorded compensator did not answer (gaps it saw)");
  inputs
      ->add_option("--compensator-process", input_options.compensator_process,
                   "Process name of the compensator in HX_STATUS (its start time bounds the warm-up)")
      ->capture_default_str();

  hystloop::replay::CommandAlteration alteration;
  CLI::App* alter = app.add_subcommand("alter", "Copy a log with one tick's u_ff_V changed");
  alter->add_option("log", log, "Recorded LCM event log")->required();
  alter->add_option("out", out, "Altered log to write")->required();
  std::optional<std::int64_t> seq;
  CLI::Option* seq_opt = alter->add_option("--seq", seq, "Tick of the command to change");
  alter->add_option("--nth", alteration.nth, "Change the nth tick commanded in the log instead (1 = first)")
      ->check(CLI::PositiveNumber)
      ->excludes(seq_opt);
  alter->add_option("--delta-V", alteration.delta_V,
                    "Add this to u_ff_V [V] (default: flip its least significant bit)");
  if (const auto exit_code = hystloop::parse_cli(app, argc, argv)) return *exit_code;

  const hystloop::ChannelNames channels(rig);
  if (inputs->parsed()) {
    const auto selection = hystloop::replay::write_replay_inputs(log, out, channels, input_options);
    std::fputs(hystloop::replay::describe(selection).c_str(), stdout);
    std::printf("first-sample %lld\n", static_cast<long long>(selection.first_answered_sample.value_or(-1)));
  } else {
    if (!seq && !alteration.nth) throw hystloop::ParameterError("--seq", "alter needs --seq or --nth");
    alteration.seq = seq.value_or(0);
    const auto r = hystloop::replay::write_altered_log(log, out, channels, alteration);
    std::printf("altered tick %lld: u_ff_V %.17g -> %.17g\n", static_cast<long long>(r.seq), r.old_u_ff_V,
                r.new_u_ff_V);
  }
  return hystloop::kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  return hystloop::run_tool("hystloop-replay-filter", [&] { return run_filter(argc, argv); });
}
