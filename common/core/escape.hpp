#pragma once
// Text from a message, made safe to put into a log line, an HX_STATUS detail or a terminal:
// printable ASCII stays, a backslash doubles (an escape in the input cannot pass for ours), every
// other byte (control bytes, terminal escape sequences, non-ASCII) becomes \xNN, and the result is
// cut at max_chars input bytes (marked "...").

#include <cstddef>
#include <limits>
#include <string>
#include <string_view>

namespace hystloop {

inline constexpr std::size_t kEscapeUncut = std::numeric_limits<std::size_t>::max();

std::string escape_wire(std::string_view text, std::size_t max_chars = 160);

}  // namespace hystloop
