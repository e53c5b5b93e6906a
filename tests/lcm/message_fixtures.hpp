#pragma once
// One fully populated, valid message of each type, deterministic in k: every field differs
// from its default and from its neighbours, so a round trip that drops or swaps a field
// shows. Shared by the unit tests and the integration probe (which checks what arrives
// against what was sent by comparing encoded bytes).

#include <cstdint>
#include <string>
#include <vector>

#include "hystloop/actuator_command_t.hpp"
#include "hystloop/control_t.hpp"
#include "hystloop/mem_params_t.hpp"
#include "hystloop/sensor_sample_t.hpp"
#include "hystloop/service_status_t.hpp"
#include "hystloop/trajectory_t.hpp"

namespace hystloop::fixtures {

inline constexpr std::int64_t kBaseUtime = 1'700'000'000'000'000;

inline double dk(std::int64_t k) { return static_cast<double>(k); }

inline sensor_sample_t sample(std::int64_t k) {
  sensor_sample_t m{};
  m.utime = kBaseUtime + 100 * k;
  m.seq = k;
  m.u_V = 12.5 + 0.25 * dk(k);
  m.y_m = -1.6e-6 + 1.0e-9 * dk(k);
  m.flags = sensor_sample_t::SIMULATED | (k % 2 == 0 ? sensor_sample_t::SLEW_LIMITED : 0);
  return m;
}

inline actuator_command_t command(std::int64_t k) {
  actuator_command_t m{};
  m.utime = kBaseUtime + 100 * k + 37;
  m.seq = k + 2;
  m.sample_seq = k;
  m.u_ff_V = 30.0 + 0.5 * dk(k);
  m.u_fb_V = -0.125 * dk(k % 7);
  m.u_V = m.u_ff_V + m.u_fb_V;
  m.y_ref_m = 1.25e-6 - 2.0e-10 * dk(k);
  m.params_version = static_cast<std::int32_t>(3 + k % 5);
  m.mode = actuator_command_t::MODE_KATALENIC;
  return m;
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
  m.c1 = 6.4e-9 + 1.0e-11 * dk(k);
  m.c2 = 2.5e-11;
  m.c3 = 1.3 + 0.01 * dk(k % 10);
  m.residual_m = 2.79e-8;
  m.samples_used = 20000 + k;
  m.window_s = 2.0;
  m.valid = (k % 3 != 0);
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
  m.mode = actuator_command_t::MODE_EXPERIMENT;
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
