#pragma once
// Shared by the re-identifier's unit tests: a small, fast configuration (10 Hz sine, 0.5 s
// window at 10 kHz: ten branches per window), MEM data from the test generator of
// tests/ident (independent of common/models), and blocks as the bridge and compensator send them.

#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "ident/mem_test_data.hpp"
#include "lcm/blocks.hpp"
#include "lcm/message_storage.hpp"
#include "reidentifier/reident_options.hpp"

namespace hystloop::testdata {

inline MemParams gain_scaled(MemParams p, double gain) {
  p.c1 *= gain;
  p.c2 *= gain;
  return p;
}

inline ReidentOptions small_reident_options(const MemParams& initial) {
  ReidentOptions o;
  o.initial = initial;
  o.rate_hz = 1e4;
  o.window_s = 0.5;
  o.capacity_s = 1.0;
  o.refit_period_s = 1.0;
  o.estimator.window_samples = 5000;
  o.estimator.capacity_samples = 10000;
  return o;
}

// 1 s of u = 250 sin(2 pi 10 t) and the MEM response of `truth` with 1 nm noise.
struct SineRecord {
  std::vector<double> u, y;
};
inline SineRecord sine_record(const MemParams& truth, std::uint64_t seed, double duration_s = 1.0) {
  SineRecord r;
  r.u = sine_input(250.0, 10.0, 1e4, duration_s);
  r.y = mem_branches(r.u, truth);
  add_noise(r.y, 1e-9, seed);
  return r;
}

constexpr double kTickPeriod_s = 1e-4;  // 10 kHz
constexpr std::int64_t kTickPeriod_us = 100;

// Blocks whose storage is reserved, as a Subscription decodes into: appending allocates nothing.
inline sensor_block_t reserved_sensor_block() {
  sensor_block_t b{};
  reserve_storage(b);
  return b;
}
inline command_block_t reserved_command_block() {
  command_block_t b{};
  reserve_storage(b);
  return b;
}

// A bridge tick that applied u_V (all feedforward, no reference) and measured y_m.
inline SensorTick sample_tick(double u_V, double y_m, std::int32_t flags = 0) {
  return SensorTick{
      .u_V = u_V, .u_ff_V = u_V, .y_ref_m = std::numeric_limits<double>::quiet_NaN(), .y_m = y_m, .flags = flags};
}

// Fills `b` with ticks seq .. seq + n - 1 of u/y from index `from` on.
inline void fill_sensor_block(sensor_block_t& b, std::int64_t seq, std::int64_t utime, const std::vector<double>& u,
                              const std::vector<double>& y, std::size_t from, std::size_t n, std::int32_t flags = 0) {
  begin_block(b, seq, utime, kTickPeriod_s);
  for (std::size_t k = from; k < from + n; ++k) append_tick(b, sample_tick(u[k], y[k], flags));
}

// Fills `b` with commands for ticks seq .. seq + n - 1, all from parameter version `version`.
inline void fill_command_block(command_block_t& b, std::int64_t seq, std::int64_t n, std::int32_t version,
                               std::int8_t mode = command_block_t::MODE_MEM) {
  begin_block(b, seq, 0, seq - 1);
  for (std::int64_t k = 0; k < n; ++k) {
    append_tick(b, CommandTick{.seq = seq + k, .u_ff_V = 0.0, .y_ref_m = 0.0, .params_version = version, .mode = mode});
  }
}

}  // namespace hystloop::testdata
