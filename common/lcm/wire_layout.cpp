#include "lcm/wire_layout.hpp"

// Each type's WireField list and its wire_layout(const T*), generated from lcmtypes/*.lcm.
#include "hystloop/wire_layout_defs.inc"

namespace hystloop {
namespace {

using F = WireField;

// LCM encodes integers big-endian.
std::int64_t read_be(const unsigned char* p, int bytes) noexcept {
  std::uint64_t v = 0;
  for (int i = 0; i < bytes; ++i) v = (v << 8) | p[i];
  if (bytes == 4) return static_cast<std::int32_t>(static_cast<std::uint32_t>(v));
  return static_cast<std::int64_t>(v);
}

}  // namespace

std::int64_t wire_fingerprint(const void* data, std::size_t size) noexcept {
  if (data == nullptr || size < 8) return 0;
  return read_be(static_cast<const unsigned char*>(data), 8);
}

std::int64_t walk_wire_layout(const WireLayout& layout, const void* data, std::size_t size) noexcept {
  if (data == nullptr || size < 8) return -1;
  const auto* bytes = static_cast<const unsigned char*>(data);
  std::size_t pos = 8;  // past the fingerprint
  std::int64_t count = -1;

  const auto take = [&](std::size_t n) noexcept {
    if (n > size - pos) return false;
    pos += n;
    return true;
  };
  const auto take_string = [&]() noexcept {
    if (4 > size - pos) return false;
    const std::int64_t length = read_be(bytes + pos, 4);
    pos += 4;
    return length >= 1 && take(static_cast<std::size_t>(length));
  };

  for (const WireField field : layout.fields) {
    bool ok = true;
    switch (field) {
      case F::kInt8: ok = take(1); break;
      case F::kInt32: ok = take(4); break;
      case F::kInt64:
      case F::kDouble: ok = take(8); break;
      case F::kString: ok = take_string(); break;
      case F::kCount:
        ok = 4 <= size - pos;
        if (ok) {
          count = read_be(bytes + pos, 4);
          pos += 4;
          ok = count >= 0 && count <= layout.max_count;
        }
        break;
      case F::kDoubleArray:
      case F::kInt64Array: ok = count >= 0 && take(static_cast<std::size_t>(count) * 8); break;
      case F::kInt32Array: ok = count >= 0 && take(static_cast<std::size_t>(count) * 4); break;
      case F::kInt8Array: ok = count >= 0 && take(static_cast<std::size_t>(count)); break;
      case F::kStringArray:
        ok = count >= 0;
        for (std::int64_t i = 0; ok && i < count; ++i) ok = take_string();
        break;
    }
    if (!ok) return -1;
  }
  return static_cast<std::int64_t>(pos);
}

}  // namespace hystloop
