#include "lcm/message_storage.hpp"

namespace hystloop {

namespace {
template <class... V>
void reserve_all(std::size_t n, V&... vectors) {
  (vectors.reserve(n), ...);
}
template <class... V>
bool all_sized(std::int32_t n, const V&... vectors) noexcept {
  return n >= 0 && ((vectors.size() == static_cast<std::size_t>(n)) && ...);
}
}  // namespace

void reserve_storage(sensor_block_t& m) {
  reserve_all(sensor_block_t::MAX_TICKS, m.u_V, m.u_ff_V, m.u_fb_V, m.y_ref_m, m.y_m, m.flags);
}

void reserve_storage(command_block_t& m) {
  reserve_all(command_block_t::MAX_TICKS, m.u_ff_V, m.y_ref_m, m.params_version, m.mode);
}

void reserve_storage(sim_truth_t& m) { m.y_true_m.reserve(sim_truth_t::MAX_TICKS); }

void clear_arrays(sensor_block_t& m) noexcept {
  m.u_V.clear();
  m.u_ff_V.clear();
  m.u_fb_V.clear();
  m.y_ref_m.clear();
  m.y_m.clear();
  m.flags.clear();
}

void clear_arrays(command_block_t& m) noexcept {
  m.u_ff_V.clear();
  m.y_ref_m.clear();
  m.params_version.clear();
  m.mode.clear();
}

void clear_arrays(sim_truth_t& m) noexcept { m.y_true_m.clear(); }

bool arrays_consistent(const sensor_block_t& m) noexcept {
  return all_sized(m.n_ticks, m.u_V, m.u_ff_V, m.u_fb_V, m.y_ref_m, m.y_m, m.flags);
}

bool arrays_consistent(const command_block_t& m) noexcept {
  return all_sized(m.n_ticks, m.u_ff_V, m.y_ref_m, m.params_version, m.mode);
}

bool arrays_consistent(const sim_truth_t& m) noexcept { return all_sized(m.n_ticks, m.y_true_m); }

void reserve_storage(trajectory_t& msg) {
  msg.points_t_s.reserve(trajectory_t::MAX_POINTS);
  msg.points_y_m.reserve(trajectory_t::MAX_POINTS);
}

void reserve_storage(mem_params_t& msg) { msg.source.reserve(kReservedStringChars); }

void reserve_storage(model_params_t& msg) {
  msg.source.reserve(kReservedStringChars);
  msg.pi_thresholds_V.reserve(model_params_t::MAX_OPERATORS);
  msg.pi_weights.reserve(model_params_t::MAX_OPERATORS);
}

void clear_arrays(model_params_t& msg) noexcept {
  msg.pi_thresholds_V.clear();
  msg.pi_weights.clear();
}

bool arrays_consistent(const model_params_t& msg) noexcept {
  const auto n = static_cast<std::size_t>(msg.n_operators);
  return msg.n_operators >= 0 && msg.pi_thresholds_V.size() == n && msg.pi_weights.size() == n;
}

void reserve_storage(service_status_t& msg) {
  msg.process.reserve(kReservedStringChars);
  msg.host.reserve(kReservedStringChars);
  msg.detail.reserve(kReservedStringChars);
  msg.counter_names.reserve(service_status_t::MAX_COUNTERS);
  msg.counter_values.reserve(service_status_t::MAX_COUNTERS);
}

void reserve_storage(control_t& msg) {
  msg.target.reserve(kReservedStringChars);
  msg.experiment.reserve(kReservedStringChars);
}

void clear_arrays(trajectory_t& msg) noexcept {
  msg.points_t_s.clear();
  msg.points_y_m.clear();
}

void clear_arrays(service_status_t& msg) noexcept {
  msg.counter_names.clear();  // destroys the strings; their heap buffers, if any, go with them
  msg.counter_values.clear();
}

bool arrays_consistent(const trajectory_t& msg) noexcept {
  return msg.n_points >= 0 && msg.points_t_s.size() == static_cast<std::size_t>(msg.n_points) &&
         msg.points_y_m.size() == static_cast<std::size_t>(msg.n_points);
}

bool arrays_consistent(const service_status_t& msg) noexcept {
  return msg.n_counters >= 0 && msg.counter_names.size() == static_cast<std::size_t>(msg.n_counters) &&
         msg.counter_values.size() == static_cast<std::size_t>(msg.n_counters);
}

}  // namespace hystloop
