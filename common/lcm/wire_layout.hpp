#pragma once
// The field layout of each message type on the wire, used to check every length field of
// a received buffer BEFORE lcm-gen's decode trusts it. The generated C++ decode resizes a
// vector to the received count before checking that the bytes are there, and computes a
// string's length minus one: a corrupted count makes it allocate gigabytes (or throw, or
// overflow) instead of failing. With the counts checked first, a corrupted buffer is a
// counted rejection and nothing else.
//
// The layouts are not written by hand: cmake/lcm_wire_layouts.py generates them from
// lcmtypes/*.lcm at build time (cmake/LcmTypes.cmake), with each type's own getHash() as the
// fingerprint, so a changed .lcm file changes its layout with it; a type the walker cannot
// check (a nested type, a count without its MAX_* bound, ...) stops the build.

#include <cstddef>
#include <cstdint>
#include <span>

namespace hystloop {

enum class WireField : std::uint8_t {
  kInt8,  // also boolean
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
  std::int64_t fingerprint;  // T::getHash() of the type this layout was generated from
  std::span<const WireField> fields;
  std::int32_t max_count;  // bound on every kCount field: the type's MAX_* constant (0 = no arrays)
};

}  // namespace hystloop

// `WireLayout wire_layout(const T*) noexcept;` for every type of lcmtypes/, with its header
// (generated into the build tree: <build>/lcmtypes/cpp/hystloop/).
#include "hystloop/wire_layout_decls.inc"  // IWYU pragma: export

namespace hystloop {

template <class T>
WireLayout wire_layout_of() noexcept {
  return wire_layout(static_cast<const T*>(nullptr));
}

// Walks a whole encoded message (8-byte fingerprint first): every fixed field fits, every
// string length is 1..remaining, every count is 0..max_count and its arrays fit. Returns
// the number of bytes the message occupies, or -1 if decoding it would not be safe.
// Does not look at the fingerprint's value. Allocation- and throw-free.
std::int64_t walk_wire_layout(const WireLayout& layout, const void* data, std::size_t size) noexcept;

// The fingerprint at the start of an encoded message, or 0 if it is shorter than 8 bytes.
std::int64_t wire_fingerprint(const void* data, std::size_t size) noexcept;

}  // namespace hystloop
