#pragma once
// One fully populated, valid message of each type, deterministic in k: every field differs
// from its default and from its neighbours, so a round trip that drops or swaps a field
// shows. Shared by the unit tests and the integration probes (which check what arrives
// against what was sent by comparing encoded bytes).
//
// Blocks: sensor_ticks(seq, n) / command_ticks(seq, n, sample_seq) build a block of any
// ticks, each tick's values a function of its tick number t (tests/java/DecodeCheck.java
// repeats the sensor formulas). sensor_block(k) / command_block(k) are round k of a probe:
// ticks 10k .. 10k + n - 1 with n = 1 + k % 10 (the array sizes vary from round to round),
// and the commands answering it (sample_seq = its last tick, so sample_seq / 10 = k).

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "hystloop/command_block_t.hpp"
#include "hystloop/control_t.hpp"
#include "hystloop/mem_params_t.hpp"
#include "hystloop/sensor_block_t.hpp"
#include "hystloop/service_status_t.hpp"
#include "hystloop/trajectory_t.hpp"
#include "lcm/blocks.hpp"

namespace hystloop::fixtures {

inline constexpr std::int64_t kBaseUtime = 1'700'000'000'000'000;
inline constexpr std::int64_t kRoundTicks = 10;    // ticks reserved per probe round
inline constexpr std::int64_t kCommandLead = 500;  // command_block(k) starts this many ticks after sensor_block(k)

inline double dk(std::int64_t k) { return static_cast<double>(k); }

// Tick t of the bridge's record (the Java check repeats u_V and y_m).
inline SensorTick sensor_tick_values(std::int64_t t) {
  SensorTick s;
  s.seq = t;
  s.u_V = 12.5 + 1.0e-3 * dk(t);
  s.u_ff_V = 12.0 + 1.0e-3 * dk(t);
  s.u_fb_V = 0.5 - 0.125 * dk(t % 7);
  s.y_ref_m = t % 5 == 4 ? std::numeric_limits<double>::quiet_NaN() : 1.25e-6 - 2.0e-13 * dk(t);
  s.y_m = -1.6e-6 + 1.0e-12 * dk(t);
  s.flags = sensor_block_t::SIMULATED | (t % 2 == 0 ? sensor_block_t::SLEW_LIMITED : 0) |
            (t % 5 == 4 ? sensor_block_t::LATE_COMMAND : 0);
  return s;
}

// Tick t of the compensator's plan.
inline CommandTick command_tick_values(std::int64_t t) {
  CommandTick c;
  c.seq = t;
  c.u_ff_V = 30.0 + 1.0e-3 * dk(t);
  c.y_ref_m = t % 9 == 8 ? std::numeric_limits<double>::quiet_NaN() : 1.25e-6 - 2.0e-13 * dk(t);
  c.params_version = static_cast<std::int32_t>(3 + t % 5);
  c.mode = t % 11 == 10 ? command_block_t::MODE_EXPERIMENT : command_block_t::MODE_KATALENIC;
  return c;
}

inline sensor_block_t sensor_ticks(std::int64_t seq, std::int64_t n_ticks) {
  sensor_block_t m{};
  begin_block(m, seq, kBaseUtime + 100 * seq, 1.0e-4);
  m.buffer_depth_ticks = static_cast<std::int32_t>(20 + seq % 7);
  for (std::int64_t t = seq; t < seq + n_ticks; ++t) append_tick(m, sensor_tick_values(t));
  return m;
}

inline command_block_t command_ticks(std::int64_t seq, std::int64_t n_ticks, std::int64_t sample_seq) {
  command_block_t m{};
  begin_block(m, seq, kBaseUtime + 100 * (sample_seq < 0 ? seq : sample_seq) + 37, sample_seq);
  for (std::int64_t t = seq; t < seq + n_ticks; ++t) append_tick(m, command_tick_values(t));
  return m;
}

inline sensor_block_t sensor_block(std::int64_t k) { return sensor_ticks(kRoundTicks * k, 1 + k % kRoundTicks); }

inline command_block_t command_block(std::int64_t k) {
  return command_ticks(kRoundTicks * k + kCommandLead, 1 + (k + 3) % kRoundTicks, last_seq(sensor_block(k)));
}

inline trajectory_t trajectory(std::int64_t k) {
  trajectory_t m{};
  m.utime = kBaseUtime + 1000 * k;
  m.version = 1 + k;
  m.shape = trajectory_t::POINTS;
  m.amplitude_m = -1.6e-6;
  m.offset_m = 0.5e-6 + 1.0e-9 * dk(k);
  m.frequency_Hz = 1.0 + dk(k % 3);
  m.phase_rad = 0.25 * dk(k % 4);
  m.start_utime = kBaseUtime + 2'000'000;
  m.blend_s = 0.5;
  m.n_points = static_cast<std::int32_t>(1 + k % 6);
  for (std::int32_t i = 0; i < m.n_points; ++i) {
    m.points_t_s.push_back(0.1 * i + 0.01 * dk(k % 3));
    m.points_y_m.push_back(1.0e-7 * i - 3.0e-7);
  }
  return m;
}

inline mem_params_t params(std::int64_t k) {
  mem_params_t m{};
  m.utime = kBaseUtime + 5'000'000 * k;
  m.version = static_cast<std::int32_t>(1 + k);
  // 0 = legacy (one publisher); any other value, negative too, is an id.
  m.publisher_id = k % 5 == 0 ? 0 : (k % 2 == 0 ? -1 : 1) * (0x5eed'0000'0000 + k);
  m.c1 = 6.4e-9 + 1.0e-11 * dk(k);
  m.c2 = 2.5e-11;
  m.c3 = 1.3 + 0.01 * dk(k % 10);
  m.residual_m = 2.79e-8;
  m.samples_used = 20000 + k;
  m.window_s = 2.0;
  m.valid = k % 3 != 0 ? 1 : 0;
  m.source = "reident@lab-host-" + std::to_string(k);
  return m;
}

inline service_status_t status(std::int64_t k) {
  service_status_t m{};
  m.utime = kBaseUtime + 1'000'000 * k;
  m.process = "compensator";
  m.host = "rig-" + std::to_string(k % 4);
  m.pid = static_cast<std::int32_t>(4242 + k);
  m.state = service_status_t::DEGRADED;
  m.detail = "late commands: " + std::to_string(k);
  m.start_utime = kBaseUtime - 3'000'000;
  m.n_counters = static_cast<std::int32_t>(k % 5);
  for (std::int32_t i = 0; i < m.n_counters; ++i) {
    m.counter_names.push_back("counter_" + std::to_string(i));
    m.counter_values.push_back(1000 * k + i);
  }
  m.loop_p50_us = 3.5;
  m.loop_p99_us = 11.25 + dk(k % 3);
  m.loop_max_us = 42.0;
  m.latency_p50_us = 61.0;
  m.latency_p99_us = 95.5;
  m.latency_max_us = 180.0 + dk(k);
  m.late = 7 + k;
  m.rejected = 2 * k;
  return m;
}

inline control_t control(std::int64_t k) {
  control_t m{};
  m.utime = kBaseUtime + 77 * k;
  m.request_id = 100 + k;
  m.command = control_t::START_EXPERIMENT;
  m.target = "compensator";
  m.mode = command_block_t::MODE_EXPERIMENT;
  m.kp = 0.5;
  m.ki = 300.0 + dk(k);
  m.kd = 1.0e-5;
  m.experiment = "sine";
  m.experiment_amplitude_V = 125.0;
  m.experiment_offset_V = 10.0 + dk(k % 2);
  m.experiment_frequency_Hz = 10.0;
  m.experiment_duration_s = 2.0;
  return m;
}

template <class T>
std::vector<std::uint8_t> encode(const T& msg) {
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(msg.getEncodedSize()));
  msg.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  return bytes;
}

}  // namespace hystloop::fixtures
