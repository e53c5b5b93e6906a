#include "lcm/blocks.hpp"

#include "lcm/message_storage.hpp"

namespace hystloop {

void begin_block(sensor_block_t& b, std::int64_t seq, std::int64_t utime, double dt_s) noexcept {
  b.utime = utime;
  b.seq = seq;
  b.dt_s = dt_s;
  b.buffer_depth_ticks = 0;
  b.n_ticks = 0;
  clear_arrays(b);
}

void begin_block(command_block_t& b, std::int64_t seq, std::int64_t utime, std::int64_t sample_seq) noexcept {
  b.utime = utime;
  b.seq = seq;
  b.sample_seq = sample_seq;
  b.n_ticks = 0;
  clear_arrays(b);
}

bool append_tick(sensor_block_t& b, const SensorTick& t) noexcept {
  if (b.n_ticks >= sensor_block_t::MAX_TICKS) return false;
  b.u_V.push_back(t.u_V);
  b.u_ff_V.push_back(t.u_ff_V);
  b.u_fb_V.push_back(t.u_fb_V);
  b.y_ref_m.push_back(t.y_ref_m);
  b.y_m.push_back(t.y_m);
  b.flags.push_back(t.flags);
  ++b.n_ticks;
  return true;
}

bool append_tick(command_block_t& b, const CommandTick& t) noexcept {
  if (b.n_ticks >= command_block_t::MAX_TICKS) return false;
  b.u_ff_V.push_back(t.u_ff_V);
  b.y_ref_m.push_back(t.y_ref_m);
  b.params_version.push_back(t.params_version);
  b.mode.push_back(t.mode);
  ++b.n_ticks;
  return true;
}

}  // namespace hystloop
