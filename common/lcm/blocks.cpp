#include "lcm/blocks.hpp"

#include "lcm/message_storage.hpp"

namespace hystloop {

void begin_block(sensor_block_t& b, std::int64_t seq, std::int64_t utime, double dt_s, int axes) noexcept {
  b.utime = utime;
  b.seq = seq;
  b.dt_s = dt_s;
  b.buffer_depth_ticks = 0;
  b.n_ticks = 0;
  b.n_axes = static_cast<std::int8_t>(axes);
  b.n_values = 0;
  clear_arrays(b);
}

void begin_block(command_block_t& b, std::int64_t seq, std::int64_t utime, std::int64_t sample_seq, int axes) noexcept {
  b.utime = utime;
  b.seq = seq;
  b.sample_seq = sample_seq;
  b.n_ticks = 0;
  b.n_axes = static_cast<std::int8_t>(axes);
  b.n_values = 0;
  clear_arrays(b);
}

bool append_tick(sensor_block_t& b, std::span<const SensorTick> ticks) noexcept {
  if (b.n_ticks >= sensor_block_t::MAX_TICKS || ticks.size() != axes_of(b) || b.n_axes < 1) return false;
  for (const SensorTick& t : ticks) {
    b.u_V.push_back(t.u_V);
    b.u_ff_V.push_back(t.u_ff_V);
    b.u_fb_V.push_back(t.u_fb_V);
    b.y_ref_m.push_back(t.y_ref_m);
    b.y_m.push_back(t.y_m);
    b.flags.push_back(t.flags);
  }
  ++b.n_ticks;
  b.n_values += b.n_axes;
  return true;
}

bool append_tick(command_block_t& b, std::span<const CommandTick> ticks) noexcept {
  if (b.n_ticks >= command_block_t::MAX_TICKS || ticks.size() != axes_of(b) || b.n_axes < 1) return false;
  for (const CommandTick& t : ticks) {
    b.u_ff_V.push_back(t.u_ff_V);
    b.y_ref_m.push_back(t.y_ref_m);
    b.params_version.push_back(t.params_version);
    b.mode.push_back(t.mode);
  }
  ++b.n_ticks;
  b.n_values += b.n_axes;
  return true;
}

bool append_tick(sensor_block_t& b, const SensorTick& t) noexcept { return append_tick(b, std::span(&t, 1)); }

bool append_tick(command_block_t& b, const CommandTick& t) noexcept { return append_tick(b, std::span(&t, 1)); }

std::vector<double> axis_truth(const sim_truth_t& b, std::size_t axis) {
  std::vector<double> y;
  const std::size_t axes = axes_of(b);
  if (axis >= axes) return y;
  y.reserve(ticks_of(b));
  for (std::size_t v = axis; v < b.y_true_m.size(); v += axes) y.push_back(b.y_true_m[v]);
  return y;
}

void begin_block(sim_truth_t& b, std::int64_t seq, std::int64_t utime, int axes) noexcept {
  b.utime = utime;
  b.seq = seq;
  b.n_ticks = 0;
  b.n_axes = static_cast<std::int8_t>(axes);
  b.n_values = 0;
  b.y_true_m.clear();
}

bool append_tick(sim_truth_t& b, std::span<const double> y_true_m) noexcept {
  if (b.n_ticks >= sim_truth_t::MAX_TICKS || y_true_m.size() != axes_of(b) || b.n_axes < 1) return false;
  for (const double y : y_true_m) b.y_true_m.push_back(y);
  ++b.n_ticks;
  b.n_values += b.n_axes;
  return true;
}

}  // namespace hystloop
