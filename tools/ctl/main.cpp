// hystloop-ctl: operate a running rig over LCM.
//
//   hystloop-ctl [--lcm-url URL] [--allow-network] [--rig PREFIX] [--key-file FILE] SUBCOMMAND [options]
//
//   status [--wait-healthy P... [--accept-safe P]... [--accept-degraded] --timeout S] [--listen S] [--counters]
//   arm | disarm | stop-experiment [--target P]      shutdown [P]      reset-counters [P]
//   mode off|MODEL                                   gains --kp --ki --kd [--notch-hz HZ --notch-q Q] [--notch2-hz
//   --notch2-q]
//                                                    [--stage-config FILE [--extra-delay-ticks N] [--force]]
//   learn on|off|reset [--target compensator]        learning for periodic references (SET_LEARNING)
//   pin-model MODEL|auto [--axis x|y|z]              the re-identifier's model choice (ctl_pin_model.hpp)
//   hold on|off [--axis x|y|z]                       the re-identifier keeps the set and model in use
//                                                    (fits and reports on, publishes nothing) or lets go
//   (MODEL: an online model, models/model_set.hpp; mode --help and pin-model --help list them)
//   experiment --amplitude V --frequency HZ --duration S [--offset V] [--kind sine|settle]
//   experiment [multisine] --kind multisine --band F_MIN:F_MAX --amplitude V_RMS [--offset V] [--period S]
//              [--periods P] [--realisations R] [--seed N] [--peak] [--odd-lines] [--ramp S]
//              a random-phase multisine for the stage's dynamics (hystloop-identify --model stage)
//   experiment --mem-paper [--duration S]           the MEM paper's 250 sin(20 pi t) V
//   experiment --banning-series [plan options] [--list] [--no-wait]   Banning et al.'s sine series
//   experiment --coupling [--amplitude V] [--out FILE]   an XY(Z) stage's cross-coupling (ctl_coupling.hpp)
//   trajectory --shape cosine|sine|triangle|hold|points --amplitude M --frequency HZ --offset M
//              --blend S [--points-csv FILE] [--corner S] [--shape-to-feasible]   |   trajectory --mem-paper
//              then waits for the compensator's verdict on HX_STATUS ([--timeout S] (3), [--no-wait],
//              [--compensator P]): exit 0 accepted or shaped (printed how), 1 refused (its reason) or
//              not confirmed in time
//   scan raster|lissajous [--width --height --lines --line-rate --slow steps|ramp | --amplitude a,b
//        --frequency f,g --duration S] [--no-decouple]   a path of every axis (HX_SCAN), then its verdict
//   (trajectory, params and experiment take --axis x|y|z on a stage of several axes)
//   params --c1 --c2 --c3 [--residual M] [--version N]
//   watch [--seconds S] [--bridge P] [--compensator P]   tracking error, late and clamped ticks, learning
//   config-get FILE KEY.PATH [--default V]   a YAML value for scripts (ctl_config_get.hpp)
//   keygen --out FILE [--force]              a new rig key, mode 0600 (README "Authenticated rig")
//
// Requests are sent 3 times a few ms apart with the same request id (UDP may drop one;
// receivers act on an id once). Exit status: 0 done, 1 failed (not healthy in time, trajectory
// refused or not confirmed, LCM error), 2 bad arguments (the message names the option).

#include <CLI/CLI.hpp>

#include <unistd.h>

#include <cstdio>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <spdlog/fmt/fmt.h>

#include "core/cli.hpp"
#include "core/config.hpp"
#include "core/errors.hpp"
#include "ctl_ack.hpp"
#include "ctl_config_get.hpp"
#include "ctl_coupling.hpp"
#include "ctl_health.hpp"
#include "ctl_link.hpp"
#include "ctl_pin_model.hpp"
#include "ctl_requests.hpp"
#include "ctl_servo_check.hpp"
#include "auth/rig_key.hpp"
#include "lcm/rig_auth.hpp"
#include "lcm/servo_gains_status.hpp"
#include "lcm/status_counters.hpp"
#include "loop/trajectory.hpp"
#include "models/axis_coupling.hpp"
#include "models/feedforward_mode.hpp"
#include "runtime/stage_config.hpp"
#include "runtime/status_reporter.hpp"

namespace {

using namespace hystloop;
using namespace hystloop::ctl;

struct Options {
  LinkOptions link;
  std::string target;
  std::string process;  // positional of shutdown / reset-counters
  std::string mode;
  GainsRequest gains;
  std::string gains_target = "bridge";  // the servo runs in the bridge
  std::string gains_stage_config;       // a YAML with the stage: section the margins are computed on
  int gains_extra_delay_ticks = 0;      // a card's read after its write: 1
  bool gains_force = false;             // send gains the loop is unstable with on that stage
  ExperimentRequest experiment;
  double multisine_period_s = 0.2;  // 5 Hz lines
  bool experiment_mem_paper = false;
  bool banning_series = false;
  bool series_list = false;
  BanningPlanOptions plan;
  SeriesRunOptions series;
  TrajectoryRequest trajectory;
  std::string points_csv;
  bool mem_paper = false;
  VerdictOptions verdict;
  std::string learning;
  std::string learn_target = "compensator";  // only the compensator learns
  ParamsRequest params;
  std::optional<std::int32_t> params_version;
  ScanRequest scan;
  int experiment_axis = 0;
  bool coupling = false;
  CouplingRunOptions coupling_run;
  double params_listen_s = 1.5;
  StatusOptions status;
  WatchOptions watch;
  AckOptions ack;
  ConfigGetOptions config_get;
  std::string keygen_out;
  bool keygen_force = false;
  std::string pin_model;  // pin-model's argument
  std::string hold;       // hold's argument: on or off
  int reident_axis = 0;   // pin-model's and hold's --axis
};

int send_control(const Options& o, std::int8_t command, const std::string& target, const std::string& what,
                 const char* owner, StateCheck state = {}, const std::function<void(control_t&)>& fill = {},
                 std::map<std::string, service_status_t>* last = nullptr) {
  const std::int64_t now = wall_utime();
  control_t msg = make_control(command, target, new_request_id(now, static_cast<int>(::getpid())), now);
  if (fill) fill(msg);
  if (check_message(msg) != Verdict::kOk) throw ParameterError(what, "refused by the message contract");
  AckOptions ack = o.ack;
  // Who answers: the target named, else the process whose command it is (none: every process heard).
  if (!target.empty() || owner != nullptr) ack.expected = {target.empty() ? std::string(owner) : target};
  ack.state = std::move(state);
  CtlLink link(o.link);
  return send_control_confirmed(link, msg, what, ack, last);
}

// Prints the servo gains `report` carries, each axis's on a stage of several; false if it carries none.
bool print_gains(const std::string& bridge, const service_status_t& report) {
  bool any = false;
  for (int axis = 0; axis < kMaxAxes; ++axis) {
    const auto g = servo_gains_from_counters([&](std::string_view name) { return find_counter(report, name); }, axis);
    if (!g) break;  // a one-axis bridge reports x's only
    any = true;
    const bool several =
        axis > 0 || servo_gains_from_counters([&](std::string_view name) { return find_counter(report, name); }, 1);
    fmt::print("hystloop-ctl: '{}' servo{} gains in force: kp {:g}, ki {:g} 1/s, kd {:g} s, {}\n", bridge,
               several ? fmt::format(" {}", axis_name(axis)) : std::string(), g->kp, g->ki_per_s, g->kd_s,
               notches_text(servo_gains(*g)));
  }
  return any;
}

// The servo's process's status report (its gains in force); nullopt, said on stderr with `why`, when
// none came within the timeout.
std::optional<service_status_t> servo_status(const Options& o, const char* why) {
  const std::string& bridge = o.gains_target;
  CtlLink link(o.link);
  StatusWait w = wait_for_status(
      link, bridge, [](const service_status_t&) { return true; }, o.ack.timeout_s);
  if (!w.satisfied) {
    std::fprintf(stderr, "hystloop-ctl: no status from '%s' on %s within %g s%s: is a rig running?\n", bridge.c_str(),
                 link.channels().status.c_str(), o.ack.timeout_s, why);
    return std::nullopt;
  }
  return std::move(w.last.at(bridge));
}

// The gains as they will be in force on each axis the request sets, checked on the stage model of
// --stage-config (ctl_servo_check.hpp): margins printed, a warning for each bound missed. 0: send;
// 1: no status to learn the gains in force from; 2: unstable on that stage and not --force.
int check_gains_on_stage(const Options& o) {
  const std::string& file = o.gains_stage_config;
  const Config config = Config::load_file(file);
  const double dt_s = config.get_in_range("compensator.dt_s", 1e-4, 1e-6, 1.0);
  const std::optional<ServoLoopModel> model =
      servo_loop_model(read_stage_model(config, StageModel{}, dt_s), dt_s, o.gains_extra_delay_ticks);
  if (!model) {
    fmt::print("hystloop-ctl: margins not checked: {} gives a stage without dynamics (stage.kind none)\n", file);
    return 0;
  }
  const std::string& bridge = o.gains_target;
  const std::optional<service_status_t> status = servo_status(o, " (the gains in force, to check the new ones with)");
  if (!status) return 1;
  const service_status_t& report = *status;
  bool unstable = false, any = false;
  for (int axis = 0; axis < kMaxAxes; ++axis) {
    const std::optional<ServoGainsFigures> in_force =
        servo_gains_from_counters([&](std::string_view name) { return find_counter(report, name); }, axis);
    if (!in_force) break;  // a one-axis bridge reports x's only
    if (o.gains.axis != control_t::EVERY_AXIS && axis != o.gains.axis) continue;
    any = true;
    const ServoCheck c = check_servo(o.gains.applied_to(*in_force), *model);
    fmt::print("hystloop-ctl: servo {} on the stage of {}{}: {}\n", axis_name(axis), file,
               o.gains_extra_delay_ticks > 0 ? fmt::format(" (+{} ticks)", o.gains_extra_delay_ticks) : "",
               describe_margins(c.margins));
    for (const std::string& warning : c.warnings) fmt::print(stderr, "hystloop-ctl: WARNING: {}\n", warning);
    unstable = unstable || !c.stable();
  }
  if (!any) {
    fmt::print("hystloop-ctl: margins not checked: '{}' reports no servo gains for that axis\n", bridge);
    return 0;
  }
  if (unstable && !o.gains_force) {
    std::fprintf(stderr,
                 "hystloop-ctl: not sent: the loop would be unstable on that stage (--force sends the gains "
                 "anyway)\n");
    return 2;
  }
  return 0;
}

int run_gains(Options& o) {
  const std::string bridge = o.gains_target;
  if (o.gains.empty()) {  // a question: the gains in force
    const std::optional<service_status_t> report = servo_status(o, "");
    if (!report) return 1;
    if (print_gains(bridge, *report)) return 0;
    std::fprintf(stderr, "hystloop-ctl: '%s' reports no servo gains (a build that does not?)\n", bridge.c_str());
    return 1;
  }
  o.gains.validate();
  if (o.gains_stage_config.empty()) {
    fmt::print(
        "hystloop-ctl: margins not checked (give --stage-config: the compensator's config, whose stage: section is "
        "the model to check them on)\n");
  } else if (const int rc = check_gains_on_stage(o); rc != 0) {
    return rc;
  }
  std::map<std::string, service_status_t> last;
  const int rc = send_control(
      o, control_t::SET_GAINS, bridge, "SET_GAINS", nullptr, {}, [&](control_t& msg) { apply(o.gains, msg); }, &last);
  if (const auto it = last.find(bridge); it != last.end()) print_gains(bridge, it->second);
  return rc;
}

int send_trajectory(const Options& o) {
  TrajectoryRequest request = o.mem_paper ? mem_paper_trajectory(o.trajectory.blend_s) : o.trajectory;
  if (!o.mem_paper && request.shape.empty()) throw ParameterError("shape", "required (or --mem-paper)");
  if (!o.points_csv.empty()) read_points_csv(o.points_csv, request);
  if (!(o.verdict.timeout_s > 0.0)) throw ParameterError("timeout", "must be > 0");
  const std::int64_t now = wall_utime();
  const trajectory_t msg = make_trajectory(request, now, now);  // version: wall time, increases per request
  std::string description = fmt::format("{} amplitude {:g} m frequency {:g} Hz offset {:g} m blend {:g} s",
                                        request.shape, msg.amplitude_m, msg.frequency_Hz, msg.offset_m, msg.blend_s);
  if (msg.n_points > 0) description += " with " + std::to_string(msg.n_points) + " points";
  if (msg.shape == trajectory_t::TRIANGLE) {
    description += msg.corner_s > 0.0 ? fmt::format(" corner {:g} s", msg.corner_s) : " corner: the shortest feasible";
  }
  if (msg.if_infeasible == trajectory_t::SHAPE) description += ", shaped if infeasible";
  CtlLink link(o.link);
  return publish_trajectory(link, msg, description, o.verdict);
}

int send_params(const Options& o) {
  ParamsRequest request = o.params;
  request.version = 1;
  request.validate();  // refuse bad values before listening for the version
  CtlLink link(o.link);
  request.version = o.params_version ? *o.params_version : next_params_version(link, o.params_listen_s);
  const mem_params_t msg = make_params(request, wall_utime());
  // The compensator reports x's set as params_version, another axis's as <axis>_params_version.
  const std::string in_use_counter = params_version_counter(request.axis);
  if (!publish_repeated(link.lcm(), link.channels().params, msg)) {
    std::fprintf(stderr, "hystloop-ctl: could not publish on %s\n", link.channels().params.c_str());
    return 1;
  }
  std::printf("hystloop-ctl: sent MEM parameters v%d c1 %g m/V c2 %g c3 %g%s on %s\n", msg.version, msg.c1, msg.c2,
              msg.c3, request.axis == 0 ? "" : (" for " + std::string(axis_name(request.axis))).c_str(),
              link.channels().params.c_str());
  std::fflush(stdout);
  if (!o.ack.wait) return 0;
  const std::string& compensator = o.verdict.compensator_process;
  const StatusWait w = wait_for_status(link, compensator, counter_is(in_use_counter, msg.version), o.ack.timeout_s);
  if (const auto r = w.last.find(reidentifier_process(request.axis));
      r != w.last.end() && find_counter(r->second, "params_held") == 0) {
    std::printf(
        "hystloop-ctl: note: the re-identifier runs and is not holding: its next refit replaces this set "
        "(hystloop-ctl hold on keeps it)\n");
  }
  if (w.satisfied) {
    std::printf("hystloop-ctl: '%s' adopted parameters v%d\n", compensator.c_str(), msg.version);
    return 0;
  }
  const auto c = w.last.find(compensator);
  if (c == w.last.end()) {
    std::fprintf(stderr, "hystloop-ctl: no status from '%s' on %s within %g s: %s\n", compensator.c_str(),
                 link.channels().status.c_str(), o.ack.timeout_s,
                 w.last.empty() ? "no rig is running" : "is the compensator running, under this name?");
    return 1;
  }
  const auto in_use = find_counter(c->second, in_use_counter);
  if (find_counter(c->second, "params_held_by_learning").value_or(0) != 0) {
    std::fprintf(stderr,
                 "hystloop-ctl: '%s' did not adopt parameters v%d (in use: %s): a set is waiting because the "
                 "running line has learned under the set in use (learning.hold_params_after); it waits until "
                 "learning stops, is reset or the line ends ('hystloop-ctl learn off' or 'learn reset' lets the "
                 "newest accepted set in at the next reversal)\n",
                 compensator.c_str(), msg.version, in_use ? ("v" + std::to_string(*in_use)).c_str() : "not reported");
    return 1;
  }
  std::fprintf(stderr,
               "hystloop-ctl: '%s' did not adopt parameters v%d within %g s (in use: %s). A set is swapped in at "
               "the next reversal of the stage's input, so a stage at rest takes it only once it moves (--no-wait "
               "sends it without waiting); refused sets are counted as params_rejected and logged with the reason\n",
               compensator.c_str(), msg.version, o.ack.timeout_s,
               in_use ? ("v" + std::to_string(*in_use)).c_str() : "not reported");
  return 1;
}

int send_scan(const Options& o) {
  if (!(o.verdict.timeout_s > 0.0)) throw ParameterError("timeout", "must be > 0");
  const std::int64_t now = wall_utime();
  const scan_t msg = make_scan(o.scan, now, now);  // version: wall time, as trajectories
  const ScanRequest& r = o.scan;
  std::string description;
  if (msg.path == scan_t::RASTER) {
    description = fmt::format("raster {:g} x {:g} m, {} lines at {:g} lines/s, {} fast, {} {}{}", r.width_m, r.height_m,
                              r.lines, r.line_rate_Hz, axis_name(r.fast_axis), axis_name(r.slow_axis),
                              r.slow == "ramp" ? "ramping" : "stepping",
                              r.corner_s > 0.0 ? fmt::format(", corners {:g} s", r.corner_s) : std::string());
  } else {
    description = fmt::format("Lissajous, amplitudes {} m at {} Hz for {:g} s", fmt::join(r.amplitude_m, "/"),
                              fmt::join(r.frequency_Hz, "/"), r.duration_s);
  }
  description += r.decouple ? ", decoupled" : ", not decoupled";
  CtlLink link(o.link);
  return publish_scan(link, msg, description, o.verdict);
}

int run_banning_series(Options& o) {
  const std::vector<SeriesStep> steps = banning_series(o.plan);
  std::size_t experiments = steps.empty() ? 0 : steps.back().experiment + 1;
  std::printf("hystloop-ctl: Banning series: %zu experiments, %zu steps, %.1f s\n", experiments, steps.size(),
              series_duration_s(steps));
  if (o.series_list) {
    for (std::size_t i = 0; i < steps.size(); ++i) std::printf("  %2zu  %s\n", i + 1, steps[i].what.c_str());
    return 0;
  }
  o.series.target = o.target;
  o.series.axis = o.experiment_axis;
  CtlLink link(o.link);
  return run_series(link, steps, o.series);
}

// An option whose default --help shows.
template <class T>
CLI::Option* with_default(CLI::App* sub, const std::string& name, T& value, const std::string& help) {
  return sub->add_option(name, value, help)->capture_default_str();
}

// Every request that changes state waits for its answer on the status channel.
void add_wait_options(CLI::App* sub, Options& o) {
  auto* no_wait = sub->add_flag(
      "--no-wait", [&o](std::int64_t) { o.ack.wait = false; },
      "Send and return at once, without waiting for the process to confirm on the status channel");
  with_default(sub, "--timeout", o.ack.timeout_s, "How long to wait for the confirmation [s]")->excludes(no_wait);
}

CLI::App* control_subcommand(CLI::App& app, const char* name, const char* help, Options& o, bool wait_options = true) {
  CLI::App* sub = app.add_subcommand(name, help);
  sub->add_option("--target", o.target, "Process the request is for (default: the process whose command it is)");
  if (wait_options) add_wait_options(sub, o);
  return sub;
}

// A command group's dispatch, made when its subcommands are added: the exit code of the one given,
// or nullopt when none of the group's was.
using CommandRun = std::function<std::optional<int>()>;

// keygen: a new rig key file (no LCM).
CommandRun add_keygen_command(CLI::App& app, Options& o) {
  CLI::App* keygen = app.add_subcommand("keygen", "Write a new rig key (mode 0600) for auth.key_file (no LCM)");
  keygen->add_option("--out", o.keygen_out, "Key file to create")->required();
  keygen->add_flag("--force", o.keygen_force,
                   "Replace an existing file (every host of the rig then needs the new key)");

  return [&o, keygen]() -> std::optional<int> {
    if (!*keygen) return std::nullopt;
    write_rig_key(o.keygen_out, generate_rig_key(), o.keygen_force);
    std::printf(
        "wrote a new rig key to %s (mode 0600): copy it to each host of the rig (keep it 0600) and set "
        "auth.key_file in every service's config\n",
        o.keygen_out.c_str());
    return 0;
  };
}

// config-get: a YAML file's value for scripts (no LCM).
CommandRun add_config_get_command(CLI::App& app, Options& o) {
  CLI::App* config_get = app.add_subcommand("config-get",
                                            "Print a YAML file's value: a scalar, a list's elements or a "
                                            "map's keys, one per line (no LCM)");
  config_get->add_option("file", o.config_get.file, "YAML file (e.g. deploy/rig.yaml)")->required();
  config_get->add_option("key", o.config_get.key, "Dotted key path (e.g. hosts.stage-pc.services)")->required();
  config_get->add_option("--default", o.config_get.default_value, "Print this when the key is absent");

  return [&o, config_get]() -> std::optional<int> {
    if (!*config_get) return std::nullopt;
    return run_config_get(o.config_get);
  };
}

// status: the processes' latest reports, or a wait until they are healthy.
CommandRun add_status_command(CLI::App& app, Options& o) {
  CLI::App* status = app.add_subcommand("status", "Print the latest HX_STATUS of each process, or wait until healthy");
  status->add_option("--wait-healthy", o.status.wait_healthy,
                     "Exit 0 as soon as each of these processes reports HEALTHY; 1 after --timeout");
  status->add_option("--accept-safe", o.status.accept_safe,
                     "Also accept SAFE from this process (e.g. an unarmed bridge)");
  status->add_flag("--accept-degraded", o.status.accept_degraded,
                   "Also accept DEGRADED (serving, with a complaint the status detail names)");
  with_default(status, "--timeout", o.status.timeout_s, "How long --wait-healthy waits [s]");
  with_default(status, "--listen", o.status.listen_s, "Without --wait-healthy: how long to collect reports [s]");
  status->add_flag("--counters", o.status.all_counters, "Also print every named counter");

  return [&o, status]() -> std::optional<int> {
    if (!*status) return std::nullopt;
    if (o.status.timeout_s <= 0 || o.status.listen_s <= 0) throw ParameterError("timeout", "must be > 0");
    CtlLink link(o.link);
    return run_status(link, o.status);
  };
}

// arm, disarm, stop-experiment, shutdown, reset-counters: one control_t command each, no argument.
CommandRun add_process_commands(CLI::App& app, Options& o) {
  CLI::App* arm = control_subcommand(app, "arm", "Bridge: leave the safe state and apply commands", o);
  CLI::App* disarm = control_subcommand(app, "disarm", "Bridge: enter the safe state now", o);
  CLI::App* stop_exp = control_subcommand(app, "stop-experiment", "Compensator: stop the identification experiment", o);
  CLI::App* shutdown = app.add_subcommand("shutdown", "Stop a process cleanly (default: every process)");
  shutdown->add_option("process", o.process, "Process to stop (default: all)");
  add_wait_options(shutdown, o);
  CLI::App* reset = app.add_subcommand("reset-counters", "Zero the status counters of a process (default: all)");
  reset->add_option("process", o.process, "Process (default: all)");
  add_wait_options(reset, o);

  return [&o, arm, disarm, stop_exp, shutdown, reset]() -> std::optional<int> {
    if (*arm) return send_control(o, control_t::ARM, o.target, "ARM", "bridge", counter_is("armed", 1));
    if (*disarm) return send_control(o, control_t::DISARM, o.target, "DISARM", "bridge", counter_is("armed", 0));
    if (*stop_exp) return send_control(o, control_t::STOP_EXPERIMENT, o.target, "STOP_EXPERIMENT", "compensator");
    if (*shutdown) return send_control(o, control_t::SHUTDOWN, o.process, "SHUTDOWN", nullptr);
    if (*reset) return send_control(o, control_t::RESET_COUNTERS, o.process, "RESET_COUNTERS", nullptr);
    return std::nullopt;
  };
}

// mode (the compensator's feedforward), pin-model and hold (the re-identifier's model and parameters).
CommandRun add_model_choice_commands(CLI::App& app, Options& o) {
  CLI::App* mode = control_subcommand(app, "mode", "Compensator: switch the feedforward model", o);
  mode->add_option("mode", o.mode, selectable_mode_choices())->required();

  CLI::App* pin = app.add_subcommand("pin-model", "Re-identifier: pin the model (no automatic change), or auto");
  pin->add_option("model", o.pin_model, pin_model_choices() + " (alias off: choose again)")->required();
  add_axis_option(pin, "--axis", o.reident_axis, "The re-identifier of this axis (default x: 'reidentifier')");
  add_wait_options(pin, o);

  CLI::App* hold = app.add_subcommand(
      "hold",
      "Re-identifier: hold the parameters and model in use (it keeps fitting and reporting, publishes nothing)");
  hold->add_option("what", o.hold, "on (hold) or off (release: publish what it fits from now on)")
      ->required()
      ->check(CLI::IsMember({"on", "off"}));
  add_axis_option(hold, "--axis", o.reident_axis, "The re-identifier of this axis (default x: 'reidentifier')");
  add_wait_options(hold, o);

  return [&o, mode, pin, hold]() -> std::optional<int> {
    if (*pin) {
      const std::int8_t m = ctl::pin_model_mode(o.pin_model);
      return send_control(o, control_t::SET_MODE, reidentifier_process(o.reident_axis), "PIN_MODEL " + o.pin_model,
                          nullptr, {}, [m](control_t& msg) { msg.mode = m; });
    }
    if (*hold) {
      const bool on = o.hold == "on";
      return send_control(o, on ? control_t::HOLD_PARAMS : control_t::RELEASE_PARAMS,
                          reidentifier_process(o.reident_axis), on ? "HOLD_PARAMS" : "RELEASE_PARAMS", nullptr,
                          counter_is("params_held", on ? 1 : 0));
    }
    if (*mode) {
      const std::int8_t m = parse_mode(o.mode);
      return send_control(o, control_t::SET_MODE, o.target, "SET_MODE " + o.mode, "compensator", counter_is("mode", m),
                          [m](control_t& msg) { msg.mode = m; });
    }
    return std::nullopt;
  };
}

// gains: the bridge's servo, set or printed.
CommandRun add_gains_command(CLI::App& app, Options& o) {
  CLI::App* gains = app.add_subcommand(
      "gains",
      "Bridge: change the servo's gains given (the others stay as in force), or print the gains in force "
      "(no gain given); normalised PID, all >= 0; kp <= 2, ki dt <= 1, kd bounded alike");
  with_default(gains, "--target", o.gains_target, "Process of the servo (the bridge)");
  gains->add_option("--kp", o.gains.kp, "Proportional gain [-]");
  gains->add_option("--ki", o.gains.ki, "Integral gain [1/s]");
  gains->add_option("--kd", o.gains.kd, "Derivative gain [s]");
  gains->add_option("--notch-hz", o.gains.notch_hz,
                    "Notch at the stage's resonance [Hz], in (0, 4500]; 0 removes the notch");
  gains->add_option("--notch-q", o.gains.notch_q, "The notch's quality factor (centre / width), in [0.1, 50]");
  gains->add_option("--notch2-hz", o.gains.notch2_hz,
                    "A second notch in cascade, at the stage's second mode [Hz], in (0, 4500]; 0 removes it");
  gains->add_option("--notch2-q", o.gains.notch2_q, "The second notch's quality factor, in [0.1, 50]");
  add_axis_option(gains, "--axis", o.gains.axis,
                  "The axis whose servo it sets (default: every axis, each keeping its own value of a gain not "
                  "given); printing: every axis's");
  gains
      ->add_option("--stage-config", o.gains_stage_config,
                   "Before sending, the loop's margins on the stage: section of this YAML (the compensator's "
                   "config; env HYSTLOOP_STAGE_CONFIG, which deploy/hystloop ctl sets): a warning under 6 dB / 40 "
                   "deg, refused when unstable")
      ->envname("HYSTLOOP_STAGE_CONFIG");
  gains->add_option("--extra-delay-ticks", o.gains_extra_delay_ticks,
                    "Ticks of delay the margins add to the simulator's one (a card's read after its write: 1)");
  gains->add_flag("--force", o.gains_force, "Send gains the loop is unstable with on the stage model");
  add_wait_options(gains, o);

  return [&o, gains]() -> std::optional<int> {
    if (!*gains) return std::nullopt;
    if (o.gains_target.empty()) throw ParameterError("target", "gains go to the bridge's servo: name its process");
    return run_gains(o);
  };
}

// learn: the compensator's learning of the feedforward.
CommandRun add_learn_command(CLI::App& app, Options& o) {
  CLI::App* learn = app.add_subcommand("learn", "Compensator: learning of the feedforward for periodic references");
  learn->add_option("what", o.learning, "on, off (drops the correction, ramped out) or reset (starts again)")
      ->required();
  with_default(learn, "--target", o.learn_target, "Process that learns (the compensator)");
  add_wait_options(learn, o);

  return [&o, learn]() -> std::optional<int> {
    if (!*learn) return std::nullopt;
    const std::int8_t l = parse_learning(o.learning);
    if (o.learn_target.empty()) throw ParameterError("target", "learning is the compensator's: name its process");
    return send_control(o, control_t::SET_LEARNING, o.learn_target, "SET_LEARNING " + o.learning, nullptr, {},
                        [l](control_t& msg) { msg.learning = l; });
  };
}

// experiment: a sine, the MEM paper's input, Banning's series or an XY(Z) stage's coupling.
CommandRun add_experiment_command(CLI::App& app, Options& o) {
  CLI::App* experiment = control_subcommand(
      app, "experiment",
      "Compensator: run an identification experiment (a sine, the MEM paper's input, or Banning's series); "
      "requests sent while one runs wait and run back to back",
      o, false);
  auto* amplitude = experiment->add_option("--amplitude", o.experiment.amplitude_V, "Excitation amplitude [V], > 0");
  auto* frequency = experiment->add_option("--frequency", o.experiment.frequency_Hz, "Excitation frequency [Hz], > 0");
  auto* duration = experiment->add_option("--duration", o.experiment.duration_s,
                                          "Duration [s], > 0, rounded up to whole periods (--mem-paper: default 2)");
  auto* offset = with_default(experiment, "--offset", o.experiment.offset_V, "Offset [V]");
  auto* kind = experiment
                   ->add_option("--kind", o.experiment.kind,
                                "sine, settle (the same sine, marked for identification to skip), or multisine")
                   ->capture_default_str();
  experiment->add_option("which", o.experiment.kind, "the experiment's kind, as --kind (e.g. multisine)")
      ->excludes(kind);
  auto* band = experiment->add_option_function<std::string>(
      "--band", [&o](const std::string& b) { ctl::parse_band(b, o.experiment); },
      "multisine: the band F_MIN:F_MAX [Hz] (lines every 1 / --period Hz in it)");
  auto* period = experiment
                     ->add_option("--period", o.multisine_period_s,
                                  "multisine: one period [s], a whole number of ticks; the frequency resolution is "
                                  "its inverse")
                     ->capture_default_str();
  auto multisine_option = [&](const char* name, auto& value, const char* help) {
    experiment->add_option(name, value, help)->capture_default_str()->needs(band);
  };
  multisine_option("--periods", o.experiment.multisine.periods,
                   "multisine: periods per realisation (the first is the transient's), >= 3");
  multisine_option("--realisations", o.experiment.multisine.realisations,
                   "multisine: realisations (new random phases; 2 or more measure the nonlinear distortion)");
  multisine_option("--seed", o.experiment.multisine.seed, "multisine: seed of the phases");
  experiment->add_flag("--peak", o.experiment.multisine.peak, "multisine: --amplitude is the peak, not the rms")
      ->needs(band);
  experiment->add_flag("--odd-lines", o.experiment.multisine.odd, "multisine: odd lines only")->needs(band);
  experiment->add_option("--ramp", o.experiment.multisine.ramp_s, "multisine: fade in and out [s] (default one period)")
      ->needs(band);
  auto* mem_paper_exp = experiment
                            ->add_flag("--mem-paper", o.experiment_mem_paper,
                                       "The MEM paper's identification input u = 250 sin(20 pi t) V")
                            ->excludes(amplitude, frequency, offset, kind);
  auto* series = experiment
                     ->add_flag("--banning-series", o.banning_series,
                                "Banning et al.'s series: offsets, small and large amplitudes (each settled "
                                "at --settle-frequency, then measured at --hysteresis-frequency), and the "
                                "frequency response; fit the log with hystloop-identify --model banning")
                     ->excludes(amplitude, frequency, duration, offset, kind, mem_paper_exp);
  auto plan_option = [&](const char* name, auto& value, const char* help) {
    with_default(experiment, name, value, help)->needs(series);
  };
  plan_option("--offsets", o.plan.offsets_V, "series: offsets of the centre experiments [V]");
  plan_option("--offset-amplitude", o.plan.offset_amplitude_V, "series: their amplitude [V]");
  plan_option("--small-amplitudes", o.plan.small_amplitudes_V, "series: small amplitudes (slope -> b) [V]");
  plan_option("--amplitudes", o.plan.amplitudes_V, "series: amplitudes (areas -> alpha) [V]");
  plan_option("--hysteresis-frequency", o.plan.hysteresis_frequency_Hz, "series: frequency of the measured loops [Hz]");
  plan_option("--measure-periods", o.plan.measure_periods, "series: periods measured per loop");
  plan_option("--settle-frequency", o.plan.settle_frequency_Hz, "series: frequency of the settling cycles [Hz]");
  plan_option("--settle-periods", o.plan.settle_periods, "series: settling cycles before each experiment (at least)");
  plan_option("--settle-path", o.plan.settle_path_V,
              "series: ... and at least this much input path, 4 x amplitude per cycle [V]");
  plan_option("--frequencies", o.plan.frequencies_Hz, "series: frequency-response points (k, c) [Hz]");
  plan_option("--frequency-amplitude", o.plan.frequency_amplitude_V, "series: their amplitude [V]");
  experiment->add_flag("--list", o.series_list, "series: print the steps and their duration, send nothing")
      ->needs(series);
  experiment->add_flag(
      "--no-wait",
      [&o](std::int64_t) {
        o.series.wait = false;
        o.ack.wait = false;
      },
      "Send and return at once (without it: wait for the compensator to confirm; a series is followed to its end)");
  with_default(experiment, "--dt", o.series.dt_s, "series: the rig's tick [s], to follow the series")->needs(series);
  auto* axis_option = add_axis_option(experiment, "--axis", o.experiment_axis,
                                      "The axis the experiment drives (default x); the others hold their references");
  auto* coupling =
      experiment
          ->add_flag("--coupling", o.coupling,
                     "The cross-coupling of an XY(Z) stage: each axis in turn a sine (--amplitude, default "
                     "100 V; --frequency, 5 Hz; --duration, 0.8 s; about --offset, 0 V) with the bridge's servo off "
                     "(its gains "
                     "put back after), every sensor recorded; prints C and, with --out, writes the "
                     "compensator's decoupling.* keys")
          ->excludes(mem_paper_exp, series, kind, axis_option);
  experiment->add_option("--out", o.coupling_run.out, "coupling: YAML file for hystloop-compensator --params")
      ->needs(coupling);
  with_default(experiment, "--rest", o.coupling_run.rest_s, "coupling: rest between the axes' experiments [s]")
      ->needs(coupling);

  return [&o, experiment, amplitude, frequency, duration, offset, band, period]() -> std::optional<int> {
    if (!*experiment) return std::nullopt;
    if (o.banning_series) return run_banning_series(o);
    if (o.coupling) {
      CouplingRunOptions& c = o.coupling_run;
      if (amplitude->count() > 0) c.amplitude_V = o.experiment.amplitude_V;
      if (frequency->count() > 0) c.frequency_Hz = o.experiment.frequency_Hz;
      if (duration->count() > 0) c.duration_s = o.experiment.duration_s;
      if (offset->count() > 0) c.offset_V = o.experiment.offset_V;
      c.timeout_s = o.ack.timeout_s;
      CtlLink link(o.link);
      return run_coupling_experiment(link, c);
    }
    if (o.experiment.kind == "multisine" || band->count() > 0) {
      if (o.experiment.kind != "multisine") {
        throw ParameterError("band", "only for a multisine (--kind multisine), not " + o.experiment.kind);
      }
      if (amplitude->count() == 0 || band->count() == 0) {
        throw ParameterError("experiment", "a multisine needs --band F_MIN:F_MAX and --amplitude");
      }
      if (frequency->count() > 0 || duration->count() > 0) {
        throw ParameterError("experiment", "a multisine takes --band and --period, not --frequency or --duration");
      }
      o.experiment.duration_s = o.multisine_period_s;
    } else if (period->count() > 0) {
      throw ParameterError("period", "only for a multisine (--kind multisine)");
    } else if (o.experiment_mem_paper) {
      o.experiment = mem_paper_experiment(o.experiment.duration_s > 0.0 ? o.experiment.duration_s : 2.0);
    } else if (amplitude->count() == 0 || frequency->count() == 0 || duration->count() == 0) {
      throw ParameterError("experiment",
                           "give --amplitude, --frequency and --duration, or --mem-paper, or "
                           "--banning-series");
    }
    o.experiment.validate();
    return send_control(o, control_t::START_EXPERIMENT, o.target, "START_EXPERIMENT", "compensator", {},
                        [&o](control_t& msg) {
                          apply(o.experiment, msg);
                          msg.axis = static_cast<std::int8_t>(o.experiment_axis);
                        });
  };
}

// trajectory and scan: a reference for one axis or a path of every axis, then the compensator's verdict.
CommandRun add_reference_commands(CLI::App& app, Options& o) {
  CLI::App* trajectory = app.add_subcommand("trajectory", "Send the reference trajectory (HX_TRAJECTORY)");
  trajectory->add_option("--shape", o.trajectory.shape, trajectory_shape_choices());
  with_default(trajectory, "--amplitude", o.trajectory.amplitude_m, "Peak amplitude [m] (may be negative)");
  with_default(trajectory, "--frequency", o.trajectory.frequency_Hz, "Frequency [Hz] of the periodic shapes");
  with_default(trajectory, "--offset", o.trajectory.offset_m, "Offset [m]");
  with_default(trajectory, "--phase", o.trajectory.phase_rad, "Phase [rad]");
  with_default(trajectory, "--blend", o.trajectory.blend_s, "Fade-in from the current reference [s]");
  trajectory->add_option("--points-csv", o.points_csv,
                         "points: CSV of t_s,y_m rows (times from the start, increasing)");
  trajectory->add_flag("--mem-paper", o.mem_paper, "The MEM paper's y_d = -1.6 um cos(2 pi t) (with --blend)")
      ->excludes("--shape");
  trajectory
      ->add_option("--corner", o.trajectory.corner_s,
                   "triangle: duration of each rounded corner [s], below half the period; 0 = the shortest the "
                   "actuator's limits allow (the compensator chooses)")
      ->capture_default_str();
  trajectory->add_flag("--shape-to-feasible", o.trajectory.shape_to_feasible,
                       "If the feedforward would leave the actuator's range or slew limit, let the compensator "
                       "shape the trajectory (smaller amplitude, rounder corners) instead of refusing it");
  auto* no_wait = trajectory->add_flag(
      "--no-wait", [&o](std::int64_t) { o.verdict.wait = false; },
      "Send and return at once, without waiting for the compensator's verdict");
  with_default(trajectory, "--timeout", o.verdict.timeout_s, "How long to wait for the compensator's verdict [s]")
      ->excludes(no_wait);
  with_default(trajectory, "--compensator", o.verdict.compensator_process,
               "Process name of the compensator in HX_STATUS");
  add_axis_option(trajectory, "--axis", o.trajectory.axis,
                  "The axis it moves (default x); the stage's other axes keep their references");

  CLI::App* scan = app.add_subcommand(
      "scan",
      "Send a path of every axis (HX_SCAN): a raster or a Lissajous figure, each axis its share of the "
      "decoupled path; then wait for the compensator's verdict");
  scan->add_option("path", o.scan.path, "raster or lissajous")
      ->required()
      ->check(CLI::IsMember({"raster", "lissajous"}));
  add_axis_option(scan, "--fast-axis", o.scan.fast_axis, "raster: the axis drawing the lines")->capture_default_str();
  add_axis_option(scan, "--slow-axis", o.scan.slow_axis, "raster: the axis stepping between them")
      ->capture_default_str();
  with_default(scan, "--width", o.scan.width_m, "raster: fast-axis travel, peak to peak [m]");
  with_default(scan, "--height", o.scan.height_m, "raster: slow-axis travel, first line to last [m]");
  with_default(scan, "--lines", o.scan.lines, "raster: lines, 2..4096");
  with_default(scan, "--line-rate", o.scan.line_rate_Hz, "raster: lines per second [Hz]");
  with_default(scan, "--slow", o.scan.slow, "raster: the slow axis steps in the corners or ramps across (steps|ramp)");
  with_default(scan, "--corner", o.scan.corner_s,
               "raster: each rounded corner [s]; 0 = the compensator's choice (two periods of the resonance)");
  with_default(scan, "--settle", o.scan.settle_s, "raster: hold at the end [s]");
  scan->add_option("--amplitude", o.scan.amplitude_m, "lissajous: peak per axis x,y[,z] [m]")->delimiter(',');
  scan->add_option("--frequency", o.scan.frequency_Hz, "lissajous: frequency per axis x,y[,z] [Hz]")->delimiter(',');
  scan->add_option("--phase", o.scan.phase_rad, "lissajous: phase per axis x,y[,z] [rad] (default 0)")->delimiter(',');
  with_default(scan, "--duration", o.scan.duration_s, "lissajous: how long it runs [s]");
  scan->add_option("--centre", o.scan.centre_m, "the path's centre per axis x,y[,z] [m] (default 0)")->delimiter(',');
  scan->add_flag(
      "--no-decouple", [&o](std::int64_t) { o.scan.decouple = false; },
      "Give each axis its own reference alone, not its share of C^-1 r (to see the coupling)");
  with_default(scan, "--blend", o.scan.blend_s, "The approach from where each axis is [s]");
  auto* scan_no_wait = scan->add_flag(
      "--no-wait", [&o](std::int64_t) { o.verdict.wait = false; },
      "Send and return at once, without waiting for the compensator's verdict");
  with_default(scan, "--timeout", o.verdict.timeout_s, "How long to wait for the compensator's verdict [s]")
      ->excludes(scan_no_wait);
  with_default(scan, "--compensator", o.verdict.compensator_process, "Process name of the compensator in HX_STATUS");

  return [trajectory, scan, &o]() -> std::optional<int> {
    if (*trajectory) return send_trajectory(o);
    if (*scan) return send_scan(o);
    return std::nullopt;
  };
}

// params: a MEM parameter set, then its adoption.
CommandRun add_params_command(CLI::App& app, Options& o) {
  CLI::App* params = app.add_subcommand("params", "Send a MEM parameter set (HX_PARAMS, valid, source hystloop-ctl)");
  params->add_option("--c1", o.params.c1, "Slope at a branch point [m/V], > 0")->required();
  params->add_option("--c2", o.params.c2, "Growth of the slope [m/V^(1+c3)], >= 0")->required();
  params->add_option("--c3", o.params.c3, "Exponent [-], in (0, 50]")->required();
  with_default(params, "--residual", o.params.residual_m, "Fit residual to report [m], >= 0");
  params->add_option("--version", o.params_version,
                     "Version (default: 1 + the highest seen on HX_PARAMS/HX_COMMAND within --listen); each run "
                     "publishes with a new publisher id, so the compensator takes it whatever others sent");
  with_default(params, "--listen", o.params_listen_s, "How long to look for the version in use [s]");
  with_default(params, "--compensator", o.verdict.compensator_process, "Process name of the compensator in HX_STATUS");
  add_axis_option(params, "--axis", o.params.axis, "The axis whose hysteresis it models (default x)");
  add_wait_options(params, o);

  return [params, &o]() -> std::optional<int> {
    if (!*params) return std::nullopt;
    return send_params(o);
  };
}

// watch: the tracking error and the loop's health, once a second.
CommandRun add_watch_command(CLI::App& app, Options& o) {
  CLI::App* watch = app.add_subcommand("watch",
                                       "Print the tracking error (from HX_SENSOR), params version, late "
                                       "commands and the bridge's lowest buffer depth once a second");
  watch->add_option("--seconds", o.watch.seconds, "Stop after this long [s] (default: until Ctrl-C)");
  with_default(watch, "--bridge", o.watch.bridge_process, "Process name of the bridge in HX_STATUS");
  with_default(watch, "--compensator", o.watch.compensator_process, "Process name of the compensator in HX_STATUS");
  add_axis_option(watch, "--axis", o.watch.axis, "The axis watched on a stage of several (default x)");

  return [&o, watch]() -> std::optional<int> {
    if (!*watch) return std::nullopt;
    require_non_negative("seconds", o.watch.seconds);
    CtlLink link(o.link);
    return run_watch(link, o.watch);
  };
}

int run(int argc, char** argv) {
  Options o;
  CLI::App app{
      "hystloop-ctl: operate a running hystloop rig over LCM (status, arm/disarm, modes, servo gains, "
      "learning, experiments, trajectories, parameters, live tracking error)"};
  app.require_subcommand(1);
  app.fallthrough();
  app.add_option("--lcm-url", o.link.lcm_url,
                 "LCM URL (default: $LCM_DEFAULT_URL, else udpm://239.255.76.67:7667?ttl=0)");
  app.add_flag("--allow-network", o.link.allow_network, "Accept an LCM URL whose packets can leave this host");
  app.add_option("--rig", o.link.rig, "Channel prefix of the rig")->capture_default_str();
  std::string key_file;
  app.add_option("--key-file", key_file,
                 "The rig key (auth.key_file of the services): sign requests, trajectories and parameters with it");

  // In the order --help lists them. keygen and config-get run before the key is read: keygen makes
  // one, config-get reads a file and needs none.
  const CommandRun keygen = add_keygen_command(app, o);
  CommandRun status = add_status_command(app, o);
  const CommandRun config_get = add_config_get_command(app, o);
  std::vector<CommandRun> rig_commands{std::move(status)};
  for (const auto add : {add_process_commands, add_model_choice_commands, add_gains_command, add_learn_command,
                         add_experiment_command, add_reference_commands, add_params_command, add_watch_command}) {
    rig_commands.push_back(add(app, o));
  }

  if (const auto exit_code = parse_cli(app, argc, argv)) return *exit_code;

  if (const auto exit_code = config_get()) return *exit_code;
  if (const auto exit_code = keygen()) return *exit_code;
  if (!key_file.empty()) set_process_rig_auth(rig_auth_from_key_file(key_file, "--key-file"));
  for (const CommandRun& run_command : rig_commands) {
    if (const auto exit_code = run_command()) return *exit_code;
  }
  return kExitUsage;
}

}  // namespace

// Setting the options up can throw too (CLI11 refuses a malformed definition): nothing escapes.
int main(int argc, char** argv) {
  return hystloop::run_tool("hystloop-ctl", [&] { return run(argc, argv); });
}
