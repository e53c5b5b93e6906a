// The compensator service's HX_CONTROL requests (mode, learning, experiments, ...), each
// acknowledged.
#include <algorithm>
#include <cmath>
#include <limits>
#include <string_view>

#include <spdlog/spdlog.h>

#include "compensator/compensator_service.hpp"
#include "compensator/scan_message.hpp"
#include "compensator/trajectory_message.hpp"
#include "core/clock.hpp"
#include "core/periodic_timer.hpp"
#include "core/process.hpp"
#include "lcm/blocks.hpp"
#include "lcm/feedforward_mode.hpp"
#include "lcm/status_counters.hpp"
#include "models/model_descriptors.hpp"

namespace hystloop {

void CompensatorService::on_control(const control_t& msg) {
  if (!filter_.accept(msg)) return;
  auto refuse = [&](const std::string& why) {
    ++counters_.control_refused;
    acks_.refused(msg.request_id, why, wall_utime());
    verdict_due_ = true;  // its sender waits for the answer
    if (const LogLimiter::Gate g = log_limiter_.allow(kLogControlRefused, monotonic_ns())) {
      spdlog::warn("control request {} (command {}) refused: {}{}", msg.request_id, msg.command, escape_wire(why),
                   suppressed_note(g));
    }
  };
  // What a request did is logged too, at most once a second (the next line says how many were not).
  auto acted = [&] { return log_limiter_.allow(kLogControl, monotonic_ns()); };
  try {
    switch (msg.command) {
      case control_t::SET_MODE: {
        const auto mode = feedforward_mode_from_wire(msg.mode);
        if (!mode || *mode == FeedforwardMode::kExperiment) {
          return refuse("mode " + std::to_string(msg.mode) + " is not selectable (" + selectable_mode_choices() + ")");
        }
        for_each_law([&](Compensator& c) { c.set_mode(*mode); });
        if (const LogLimiter::Gate g = acted()) {
          spdlog::info("mode {} (request {}){}", to_string(x().mode()), msg.request_id, suppressed_note(g));
        }
        break;
      }
      case control_t::START_EXPERIMENT: {
        const ExperimentSpec e =
            make_experiment_spec(msg.experiment, msg.experiment_amplitude_V, msg.experiment_offset_V,
                                 msg.experiment_frequency_Hz, msg.experiment_duration_s);
        Compensator& driven = law(msg.axis, "control.axis");
        if (settings_.axes > 1 && scan_running()) {
          return refuse("a scan is running: an experiment on one axis would tear the path the others follow");
        }
        const bool queued = driven.experiment_running();
        driven.start_experiment(e);
        if (const LogLimiter::Gate g = acted()) {
          const std::string when =
              queued ? "queued, " + std::to_string(driven.experiments_queued()) + " waiting" : "started";
          if (e.multisine) {
            spdlog::info("experiment {}: {} V {} about {} V, {} .. {} Hz, period {} s {} (request {}){}",
                         escape_wire(msg.experiment), e.amplitude_V, e.ms.peak ? "peak" : "rms", e.offset_V,
                         e.ms.f_min_hz, e.frequency_hz, e.duration_s, when, msg.request_id, suppressed_note(g));
          } else {
            spdlog::info("experiment {} {} V + {} V at {} Hz for {} s {} (request {}){}", escape_wire(msg.experiment),
                         e.amplitude_V, e.offset_V, e.frequency_hz, e.duration_s, when, msg.request_id,
                         suppressed_note(g));
          }
        }
        break;
      }
      case control_t::STOP_EXPERIMENT: {
        // Whichever axis runs one: an operator's stop ends every excitation of the stage.
        std::size_t queued = 0;
        for_each_law([&](Compensator& c) {
          queued += c.experiments_queued();
          c.stop_experiment();
        });
        if (const LogLimiter::Gate g = acted()) {
          spdlog::info("experiment stopped, {} queued dropped (request {}){}", queued, msg.request_id,
                       suppressed_note(g));
        }
        break;
      }
      case control_t::SET_LEARNING:
        switch (msg.learning) {
          case control_t::LEARNING_OFF: for_each_law([](Compensator& c) { c.set_learning(false); }); break;
          case control_t::LEARNING_ON: for_each_law([](Compensator& c) { c.set_learning(true); }); break;
          case control_t::LEARNING_RESET: for_each_law([](Compensator& c) { c.reset_learning(); }); break;
          default: return refuse("learning " + std::to_string(msg.learning) + " is not off (0), on (1) or reset (2)");
        }
        if (const LogLimiter::Gate g = acted()) {
          spdlog::info("learning {} (request {}){}",
                       msg.learning == control_t::LEARNING_RESET ? "reset" : (msg.learning ? "on" : "off"),
                       msg.request_id, suppressed_note(g));
        }
        break;
      case control_t::RESET_COUNTERS:
        reported_.rebase(collect_counters());
        reported_.rebase("sensor", samples_.counters());
        reported_.rebase("trajectory", trajectories_.counters());
        reported_.rebase("scan", scans_.counters());
        reported_.rebase("params", params_.counters());
        reported_.rebase("control", control_.counters());
        reported_.rebase("command", command_pub_.counters());
        if (const LogLimiter::Gate g = acted()) {
          spdlog::info("RESET_COUNTERS (request {}){}", msg.request_id, suppressed_note(g));
        }
        break;
      case control_t::SHUTDOWN:
        spdlog::info("SHUTDOWN (request {})", msg.request_id);
        request_stop();
        break;
      default:  // the bridge's (ARM, DISARM, SET_GAINS: the servo runs beside the sensor)
        if (msg.target == "compensator") return refuse("not a compensator command (the bridge's)");
        return;
    }
    ++counters_.control_acted;
    acks_.acted(msg.request_id);
    verdict_due_ = true;
  } catch (const std::exception& e) {
    refuse(e.what());
  }
  report_if_due();
}

}  // namespace hystloop
