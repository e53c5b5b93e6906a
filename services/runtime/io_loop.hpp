#pragma once
// The I/O loop of a service: dispatch LCM messages as they come, run periodic work
// (the 1 Hz status report) on time, and return when SIGINT/SIGTERM or a SHUTDOWN
// request arrives. Never blocks in LCM's handle(): it waits on LCM's file descriptor
// with a timeout (see common/lcm/connection.hpp).

#include <chrono>
#include <functional>

#include <lcm/lcm-cpp.hpp>

namespace hystloop {

struct IoLoopOptions {
  std::chrono::microseconds poll_timeout{1000};  // upper bound on one wait
  std::chrono::milliseconds period{1000};        // how often on_period runs
};

// Runs until stop_requested(). on_period is called every options.period (first after one
// period) with the wall time in us, after the keyless service's network watch
// (keyless_network_reached, runtime/rig_auth_config.hpp), which may request the stop; `after_dispatch` (optional) after
// each batch of messages. Returns the number of LCM errors seen.
int run_io_loop(lcm::LCM& lcm, const IoLoopOptions& options, const std::function<void(std::int64_t)>& on_period,
                const std::function<void()>& after_dispatch = {});

}  // namespace hystloop
