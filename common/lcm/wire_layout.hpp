#pragma once
// The field layout of each message type on the wire, used to check every length field of
// a received buffer BEFORE lcm-gen's decode trusts it. The generated C++ decode resizes a
// vector to the received count before checking that the bytes are there, and computes a
// string's length minus one: a corrupted count makes it allocate gigabytes (or throw, or
// overflow) instead of failing. With the counts checked first, a corrupted buffer is a
// counted rejection and nothing else.
//
// A layout is pinned to the type's fingerprint: when a .lcm file changes, layout_matches()
// fails (and Subscription refuses to start) until the layout here is updated with it.

#include <cstddef>
#include <cstdint>
#include <span>

#include "hystloop/command_block_t.hpp"
#include "hystloop/control_t.hpp"
#include "hystloop/mem_params_t.hpp"
#include "hystloop/sensor_block_t.hpp"
#include "hystloop/service_status_t.hpp"
#include "hystloop/trajectory_t.hpp"

namespace hystloop {

enum class WireField : std::uint8_t {
  kInt8,         // also boolean
  kInt32,
  kInt64,
  kDouble,
  kString,       // int32 length including the NUL, then the bytes
  kCount,        // int32 element count of the arrays that follow, 0..max_count
  kDoubleArray,  // [count] doubles
  kInt64Array,   // [count] int64
  kInt32Array,   // [count] int32
  kInt8Array,    // [count] int8
  kStringArray,  // [count] strings
};

struct WireLayout {
  std::int64_t fingerprint;  // T::getHash() this layout was written for
  std::span<const WireField> fields;
  std::int32_t max_count;    // bound on every kCount field
};

WireLayout wire_layout(const sensor_block_t*) noexcept;
WireLayout wire_layout(const command_block_t*) noexcept;
WireLayout wire_layout(const trajectory_t*) noexcept;
WireLayout wire_layout(const mem_params_t*) noexcept;
WireLayout wire_layout(const service_status_t*) noexcept;
WireLayout wire_layout(const control_t*) noexcept;

template <class T>
WireLayout wire_layout_of() noexcept {
  return wire_layout(static_cast<const T*>(nullptr));
}

// True if `T`'s generated fingerprint is the one its layout was written for.
template <class T>
bool layout_matches() noexcept {
  return wire_layout_of<T>().fingerprint == T::getHash();
}

// Walks a whole encoded message (8-byte fingerprint first): every fixed field fits, every
// string length is 1..remaining, every count is 0..max_count and its arrays fit. Returns
// the number of bytes the message occupies, or -1 if decoding it would not be safe.
// Does not look at the fingerprint's value. Allocation- and throw-free.
std::int64_t walk_wire_layout(const WireLayout& layout, const void* data, std::size_t size) noexcept;

// The fingerprint at the start of an encoded message, or 0 if it is shorter than 8 bytes.
std::int64_t wire_fingerprint(const void* data, std::size_t size) noexcept;

}  // namespace hystloop
