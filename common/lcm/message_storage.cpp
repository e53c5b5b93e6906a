#include "lcm/message_storage.hpp"

namespace hystloop {

namespace {
template <class... V>
void reserve_all(std::size_t n, V&... vectors) {
  (vectors.reserve(n), ...);
}
template <class... V>
void clear_all(V&... vectors) noexcept {
  (vectors.clear(), ...);
}
template <class... V>
bool all_sized(std::int32_t n, const V&... vectors) noexcept {
  return n >= 0 && ((vectors.size() == static_cast<std::size_t>(n)) && ...);
}
}  // namespace

void reserve_storage(sensor_block_t& m) {
  reserve_all(std::size_t{sensor_block_t::MAX_TICKS} * sensor_block_t::MAX_AXES, m.u_V, m.u_ff_V, m.u_fb_V, m.y_ref_m,
              m.y_m, m.flags);
}

void reserve_storage(command_block_t& m) {
  reserve_all(std::size_t{command_block_t::MAX_TICKS} * command_block_t::MAX_AXES, m.u_ff_V, m.y_ref_m,
              m.params_version, m.mode);
}

void reserve_storage(sim_truth_t& m) { m.y_true_m.reserve(sim_truth_t::MAX_VALUES); }

void clear_arrays(sensor_block_t& m) noexcept { clear_all(m.u_V, m.u_ff_V, m.u_fb_V, m.y_ref_m, m.y_m, m.flags); }

void clear_arrays(command_block_t& m) noexcept { clear_all(m.u_ff_V, m.y_ref_m, m.params_version, m.mode); }

void clear_arrays(sim_truth_t& m) noexcept { m.y_true_m.clear(); }

namespace {
// n_values is what LCM sizes the arrays by; it must also be n_ticks x n_axes, or a block's ticks
// and axes would not be what its arrays hold.
bool values_of_ticks(std::int32_t n_ticks, std::int8_t n_axes, std::int32_t n_values) noexcept {
  return n_ticks >= 0 && n_axes >= 1 && static_cast<std::int64_t>(n_ticks) * n_axes == n_values;
}
}  // namespace

bool arrays_consistent(const sensor_block_t& m) noexcept {
  return values_of_ticks(m.n_ticks, m.n_axes, m.n_values) &&
         all_sized(m.n_values, m.u_V, m.u_ff_V, m.u_fb_V, m.y_ref_m, m.y_m, m.flags);
}

bool arrays_consistent(const command_block_t& m) noexcept {
  return values_of_ticks(m.n_ticks, m.n_axes, m.n_values) &&
         all_sized(m.n_values, m.u_ff_V, m.y_ref_m, m.params_version, m.mode);
}

bool arrays_consistent(const sim_truth_t& m) noexcept {
  return values_of_ticks(m.n_ticks, m.n_axes, m.n_values) && all_sized(m.n_values, m.y_true_m);
}

void reserve_storage(trajectory_t& msg) { reserve_all(trajectory_t::MAX_POINTS, msg.points_t_s, msg.points_y_m); }

void reserve_storage(mem_params_t& msg) { msg.source.reserve(kReservedStringChars); }

void reserve_storage(model_params_t& msg) {
  msg.source.reserve(kReservedStringChars);
  reserve_all(model_params_t::MAX_OPERATORS, msg.pi_thresholds_V, msg.pi_weights);
}

void clear_arrays(model_params_t& msg) noexcept { clear_all(msg.pi_thresholds_V, msg.pi_weights); }

bool arrays_consistent(const model_params_t& msg) noexcept {
  return all_sized(msg.n_operators, msg.pi_thresholds_V, msg.pi_weights);
}

void reserve_storage(service_status_t& msg) {
  reserve_all(kReservedStringChars, msg.process, msg.host, msg.detail);
  reserve_all(service_status_t::MAX_COUNTERS, msg.counter_names, msg.counter_values);
}

void reserve_storage(control_t& msg) { reserve_all(kReservedStringChars, msg.target, msg.experiment); }

void clear_arrays(trajectory_t& msg) noexcept { clear_all(msg.points_t_s, msg.points_y_m); }

// Clearing counter_names destroys the strings; their heap buffers, if any, go with them.
void clear_arrays(service_status_t& msg) noexcept { clear_all(msg.counter_names, msg.counter_values); }

bool arrays_consistent(const trajectory_t& msg) noexcept {
  return all_sized(msg.n_points, msg.points_t_s, msg.points_y_m);
}

bool arrays_consistent(const service_status_t& msg) noexcept {
  return all_sized(msg.n_counters, msg.counter_names, msg.counter_values);
}

}  // namespace hystloop
