#include "reidentifier/reident_options.hpp"

#include <cmath>
#include <string>
#include <vector>

#include "runtime/config_validation.hpp"

namespace hystloop {

namespace {
constexpr const char* kReidentKeys[] = {
    "reident.rate_hz",          "reident.refit_period_s",           "reident.window_s",
    "reident.capacity_s",       "reident.holdout_branches",         "reident.min_relative_improvement",
    "reident.max_residual_rms_m", "reident.max_solver_time_s", "reident.reversal_dead_band_V",      "reident.publish_invalid",
    "reident.stale_after_s",    "reident.degraded_after_poisoned", "reident.lcm_queue",
};

std::size_t samples_of(double seconds, double rate_hz) {
  return static_cast<std::size_t>(std::llround(seconds * rate_hz));
}
}  // namespace

ReidentOptions read_reident_options(const Config& config) {
  std::vector<std::string> known(std::begin(kReidentKeys), std::end(kReidentKeys));
  for (const std::string& key : config.keys()) {
    if (key.rfind("reident.", 0) != 0) known.push_back(key);
  }
  config.check_no_unknown_keys(known);

  ReidentOptions o;
  const MemParams d = MemParams::paper_like();
  o.initial.c1 = config.get_positive("mem.c1", d.c1);
  o.initial.c2 = config.get_non_negative("mem.c2", d.c2);
  o.initial.c3 = config.get_positive("mem.c3", d.c3);
  validate_config_section(config, "mem.", [&] { o.initial.validate(); });

  o.rate_hz = config.get_in_range("reident.rate_hz", o.rate_hz, 1.0, 1e6);
  o.refit_period_s = config.get_in_range("reident.refit_period_s", o.refit_period_s, 0.01, 3600.0);
  o.window_s = config.get_in_range("reident.window_s", o.window_s, 1e-6, 3600.0);
  o.capacity_s = config.get_in_range("reident.capacity_s", o.capacity_s, 1e-6, 3600.0);
  o.publish_invalid = config.get<bool>("reident.publish_invalid", o.publish_invalid);
  o.stale_after_s = config.get_in_range("reident.stale_after_s", o.stale_after_s, 0.001, 3600.0);
  o.degraded_after_poisoned = config.get_int_in_range("reident.degraded_after_poisoned", o.degraded_after_poisoned, 1,
                                                      1000000);
  o.lcm_queue = config.get_int_in_range("reident.lcm_queue", o.lcm_queue, 100, 10000000);

  OnlineMemOptions& e = o.estimator;
  e.window_samples = samples_of(o.window_s, o.rate_hz);
  if (e.window_samples < 16) {
    config.fail("reident.window_s", "must hold at least 16 samples at reident.rate_hz (got " +
                                        std::to_string(e.window_samples) + ")");
  }
  e.capacity_samples = samples_of(o.capacity_s, o.rate_hz);
  if (e.capacity_samples < e.window_samples) {
    config.fail("reident.capacity_s", "must be >= reident.window_s (got " + std::to_string(o.capacity_s) + " s < " +
                                          std::to_string(o.window_s) + " s)");
  }
  if (e.capacity_samples > 100'000'000) config.fail("reident.capacity_s", "must hold at most 1e8 samples");
  e.holdout_branches =
      static_cast<std::size_t>(config.get_int_in_range("reident.holdout_branches", 1, 1, 1000));
  e.min_relative_improvement =
      config.get_in_range("reident.min_relative_improvement", e.min_relative_improvement, 0.0, 0.99);
  e.max_residual_rms_m = config.get_in_range("reident.max_residual_rms_m", e.max_residual_rms_m, 1e-15, 1.0);
  e.fit.max_solver_time_s = config.get_in_range("reident.max_solver_time_s", e.fit.max_solver_time_s, 1e-4, 60.0);
  // With feedback on, u carries small jitter: reversals smaller than this are not branches.
  e.fit.reversal_dead_band_V =
      config.get_in_range("reident.reversal_dead_band_V", e.fit.reversal_dead_band_V, 0.0, 100.0);
  // The field names of OnlineMemOptions are not the file's: a refusal here would be a bug above.
  e.validate();
  return o;
}

}  // namespace hystloop
