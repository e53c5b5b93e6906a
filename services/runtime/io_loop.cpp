#include "runtime/io_loop.hpp"

#include <algorithm>

#include "core/process.hpp"
#include "lcm/connection.hpp"
#include "runtime/rig_auth_config.hpp"
#include "runtime/status_reporter.hpp"

namespace hystloop {

int run_io_loop(lcm::LCM& lcm, const IoLoopOptions& options, const std::function<void(std::int64_t)>& on_period,
                const std::function<void()>& after_dispatch) {
  using clock = std::chrono::steady_clock;
  int errors = 0;
  auto next = clock::now() + options.period;
  while (!stop_requested()) {
    const auto left = std::chrono::duration_cast<std::chrono::microseconds>(next - clock::now());
    const int n = handle_pending(lcm, std::clamp(left, std::chrono::microseconds(0), options.poll_timeout));
    if (n < 0) ++errors;
    if (n > 0 && after_dispatch) after_dispatch();
    if (clock::now() >= next) {
      next += options.period;
      keyless_network_reached();  // a keyless service that finds itself on a network stops
      if (on_period) on_period(wall_utime());
    }
  }
  return errors;
}

}  // namespace hystloop
