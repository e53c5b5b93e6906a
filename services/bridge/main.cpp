// hystloop-bridge: the 10 kHz clock, the stage (simulated: Banning or Ramberg-Osgood; or a DAQ card through comedi),
// the actuator limits and the watchdog. See services/bridge/README.md.
#include <CLI/CLI.hpp>

#include <cstdio>
#include <stdexcept>

#include <spdlog/spdlog.h>

#include "bridge/bridge_service.hpp"
#include "bridge/latency_test.hpp"
#include "bridge/probe_hardware.hpp"
#include "core/cli.hpp"
#include "core/process.hpp"
#include "lcm/connection.hpp"
#include "runtime/service_main.hpp"
#include "runtime/service_options.hpp"

int main(int argc, char** argv) try {
  using namespace hystloop;
  CLI::App app{
      "hystloop-bridge: owns the loop's clock. Buffers the feedforward and reference that HX_COMMAND sends "
      "ahead of time, adds its servo (PI/PID on y_ref - y) at every tick, clamps, applies, samples the stage "
      "and publishes HX_SENSOR in blocks. Starts in the safe state: arm it with an ARM request on HX_CONTROL "
      "(or --auto-arm)."};
  ServiceOptions options;
  add_service_options(app, options);
  std::string backend, noise, drift, seconds, summary_json;
  bool auto_arm = false;
  app.add_option(
      "--backend", backend,
      "Stage backend: sim (Banning stage), ro (Ramberg-Osgood), series (any hysteresis, then any linear stage with a "
      "delay: plant.*) or comedi (a DAQ card: comedi.*) [bridge.backend]");
  app.add_option("--noise-rms-m", noise, "Sensor noise RMS [m] [bridge.noise_rms_m]");
  app.add_option("--drift", drift, "Gain drift over bridge.drift_duration_s, e.g. 0.1 = +10 % [bridge.drift_fraction]");
  app.add_option("--seconds", seconds, "Stop after this many seconds [bridge.run_seconds]");
  app.add_option("--summary-json", summary_json,
                 "At exit, write the run's figures (ticks, late, watchdog trips, lowest buffer depth, block-to-answer "
                 "latency, CPU) to this JSON file");
  app.add_flag("--auto-arm", auto_arm, "Arm as soon as commands flow (first arm only) [bridge.auto_arm]");
  // Setting up a comedi card (bridge.backend: comedi): see services/bridge/README.md.
  bool probe = false;
  std::string device;
  ProbeOptions probe_options;
  app.add_flag("--probe-hardware", probe,
               "List the comedi card (subdevices, channels, ranges, calibration) and exit; with --yes also drive a "
               "slow, clamped triangle and report the sensor's gain and sign against the command");
  app.add_option("--device", device, "Comedi device file [comedi.device]");
  app.add_flag("--yes", probe_options.drive,
               "With --probe-hardware: really drive the output (the amplifier is enabled)");
  app.add_option("--amplitude-V", probe_options.amplitude_V,
                 "With --probe-hardware --yes: the triangle's amplitude at the card [V]")
      ->check(CLI::Range(0.0, 10.0));
  app.add_option("--duration-s", probe_options.duration_s, "With --probe-hardware --yes: the triangle's duration [s]")
      ->check(CLI::Range(0.05, 60.0));
  add_axis_option(&app, "--axis", probe_options.axis,
                  "With --probe-hardware: the axis probed (default x; the others are held at their safe voltage)");
  double latency_test_s = 0.0;
  app.add_option("--latency-test", latency_test_s,
                 "Run the backend's real tick (the card's write and read) for this many seconds, never armed (every "
                 "output at its safe voltage, no LCM), then print the wake-up lateness and the tick's work "
                 "(percentiles, histogram), the skipped ticks and a verdict; exit 0 fit to arm, 1 not "
                 "(docs/TIMING.md, \"Real-time host\")")
      ->check(CLI::Range(0.1, 86400.0));
  if (const auto exit_code = parse_command_line(app, argc, argv)) return *exit_code;

  // Flags are overrides of their config keys, so every value is validated in one place.
  if (!backend.empty()) options.overrides.push_back("bridge.backend=" + backend);
  if (!noise.empty()) options.overrides.push_back("bridge.noise_rms_m=" + noise);
  if (!drift.empty()) options.overrides.push_back("bridge.drift_fraction=" + drift);
  if (!seconds.empty()) options.overrides.push_back("bridge.run_seconds=" + seconds);
  if (auto_arm) options.overrides.push_back("bridge.auto_arm=true");
  if (!device.empty()) options.overrides.push_back("comedi.device=" + device);
  if (probe) {  // the comedi.* keys of the config, whatever its backend
    options.overrides.push_back("bridge.backend=comedi");
    options.overrides.push_back("rt.ticks_per_wake=1");
  }

  BridgeSettings settings;
  std::string url;
  const auto refused = configure_or_refuse("hystloop-bridge", [&] {
    // The probe drives the card alone: no LCM, so no rig authentication.
    url = set_up_service("bridge", options,
                         {.adjust = {},
                          .read = [&](const Config& config) { settings = load_bridge_settings(config); },
                          .rig_auth = !probe && latency_test_s == 0.0});
  });
  if (refused) return *refused;

  if (probe) return probe_hardware(settings, probe_options, stdout);
  // mlockall as configured; refused where real time is required (before the card is opened).
  const auto lock_memory_as_configured = [&] {
    if (!settings.rt.lock_memory) return;
    const SetupStatus locked = lock_memory();
    if (!locked.ok && settings.rt.required) throw std::runtime_error(real_time_refused(locked.detail));
    spdlog::info("memory: {}", locked.detail);
  };
  if (latency_test_s > 0.0) {
    return run_service([&] {
      lock_memory_as_configured();
      return run_latency_test(settings, latency_test_s, stdout);
    });
  }

  return run_service([&] {
    lock_memory_as_configured();
    if (settings.rt.io_priority > 0) {
      // Before LCM starts: its receive thread inherits the I/O thread's scheduling.
      spdlog::info("I/O thread: {}", set_realtime_priority(settings.rt.io_priority).detail);
    }
    const ChannelNames channels(options.rig_prefix);
    auto lcm = open_lcm(url, options.allow_network);
    spdlog::info("lcm: {}", url);
    BridgeService service(settings, *lcm, channels);
    service.write_summary_to(summary_json);
    return service.run();
  });
} catch (...) {  // CLI11's set-up, before the handlers above exist: nothing escapes main
  return hystloop::exit_on_escaped_exception("hystloop-bridge");
}
