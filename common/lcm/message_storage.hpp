#pragma once
// Storage of the variable-size types.
//
// reserve_storage: capacity reserved up front in a message that is decoded into again and again, so that
// decoding the largest message the contract allows does not allocate after construction.
// Fixed-size types need nothing. Strings longer than `kReservedStringChars` still allocate
// (status and control are 1 Hz / on-demand channels).

#include <cstddef>

#include "hystloop/command_block_t.hpp"
#include "hystloop/control_t.hpp"
#include "hystloop/mem_params_t.hpp"
#include "hystloop/model_params_t.hpp"
#include "hystloop/scan_t.hpp"
#include "hystloop/sensor_block_t.hpp"
#include "hystloop/service_status_t.hpp"
#include "hystloop/sim_truth_t.hpp"
#include "hystloop/trajectory_t.hpp"

namespace hystloop {

inline constexpr std::size_t kReservedStringChars = 64;

void reserve_storage(sensor_block_t& msg);
void reserve_storage(command_block_t& msg);
void reserve_storage(sim_truth_t& msg);
void reserve_storage(trajectory_t& msg);
void reserve_storage(mem_params_t& msg);
void reserve_storage(model_params_t& msg);
void reserve_storage(service_status_t& msg);
void reserve_storage(control_t& msg);
inline void reserve_storage(scan_t&) {}  // fixed-size arrays only

// clear_arrays: empties every variable array, keeping its capacity. Needed before decoding
// into a reused message: lcm-gen's decode skips a primitive array whose count is 0, so it
// would keep the previous message's elements.
void clear_arrays(sensor_block_t& msg) noexcept;
void clear_arrays(command_block_t& msg) noexcept;
void clear_arrays(sim_truth_t& msg) noexcept;
inline void clear_arrays(mem_params_t&) noexcept {}
void clear_arrays(model_params_t& msg) noexcept;
inline void clear_arrays(control_t&) noexcept {}
inline void clear_arrays(scan_t&) noexcept {}
void clear_arrays(trajectory_t& msg) noexcept;
void clear_arrays(service_status_t& msg) noexcept;

// arrays_consistent: every variable array holds exactly its count (lcm-gen's encode reads
// `count` elements whatever the vector's size). Publisher refuses an inconsistent
// message even when its value check is switched off.
bool arrays_consistent(const sensor_block_t& msg) noexcept;
bool arrays_consistent(const command_block_t& msg) noexcept;
bool arrays_consistent(const sim_truth_t& msg) noexcept;
inline bool arrays_consistent(const mem_params_t&) noexcept { return true; }
bool arrays_consistent(const model_params_t& msg) noexcept;
inline bool arrays_consistent(const control_t&) noexcept { return true; }
inline bool arrays_consistent(const scan_t&) noexcept { return true; }
bool arrays_consistent(const trajectory_t& msg) noexcept;
bool arrays_consistent(const service_status_t& msg) noexcept;

}  // namespace hystloop
