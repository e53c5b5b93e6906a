#include "runtime/log_limiter.hpp"

namespace hystloop {

LogLimiter::Gate LogLimiter::allow(std::size_t reason, std::int64_t now_ns) noexcept {
  Slot& s = slots_[reason < kMaxReasons ? reason : kMaxReasons - 1];
  // A clock that went back (now_ns < last_ns) lets the line through: never silent for long.
  if (s.written && now_ns >= s.last_ns && now_ns - s.last_ns < interval_ns_) {
    ++s.suppressed;
    ++suppressed_total_;
    return {};
  }
  Gate g{true, s.suppressed};
  s.written = true;
  s.last_ns = now_ns;
  s.suppressed = 0;
  return g;
}

std::string suppressed_note(const LogLimiter::Gate& gate) {
  if (!gate.write || gate.suppressed == 0) return {};
  return "; " + std::to_string(gate.suppressed) + " more suppressed";
}

std::string escape_wire(std::string_view text, std::size_t max_chars) {
  static constexpr char kHex[] = "0123456789abcdef";
  const bool cut = text.size() > max_chars;
  if (cut) text = text.substr(0, max_chars);
  std::string out;
  out.reserve(text.size() + 8);
  for (const char ch : text) {
    const auto c = static_cast<unsigned char>(ch);
    if (c == '\\') {
      out += "\\\\";
    } else if (c >= 0x20 && c < 0x7f) {
      out += ch;
    } else {
      out += "\\x";
      out += kHex[c >> 4];
      out += kHex[c & 0xf];
    }
  }
  if (cut) out += "...";
  return out;
}

}  // namespace hystloop
