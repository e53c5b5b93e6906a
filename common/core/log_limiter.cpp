#include "core/log_limiter.hpp"

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

}  // namespace hystloop
