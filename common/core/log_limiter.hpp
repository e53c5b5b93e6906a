#pragma once
// Log hygiene for what arrives off the wire. A service under malformed or hostile input must not
// flood its log: LogLimiter lets at most one line per reason through per interval (1 s), and the
// next line let through says how many of that reason were suppressed since the last one.
// escape_wire() (core/escape.hpp) makes text from a message safe to put into a log line.
//
// Reasons are small integers (an enum's value, < kMaxReasons) chosen by the service. Time is an
// argument (a steady clock in ns). No allocation, lock or throw in allow().

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "core/escape.hpp"

namespace hystloop {

class LogLimiter {
 public:
  static constexpr std::size_t kMaxReasons = 32;

  struct Gate {
    bool write = false;            // write this line
    std::uint64_t suppressed = 0;  // lines of this reason suppressed before it (when write)
    explicit operator bool() const noexcept { return write; }
  };

  explicit LogLimiter(std::int64_t interval_ns = 1'000'000'000) noexcept : interval_ns_(interval_ns) {}

  // A line for `reason` at now_ns: written when none of that reason was written within the
  // interval before; otherwise counted as suppressed. A reason >= kMaxReasons shares the last slot.
  Gate allow(std::size_t reason, std::int64_t now_ns) noexcept;

  std::uint64_t suppressed_total() const noexcept { return suppressed_total_; }

 private:
  struct Slot {
    bool written = false;
    std::int64_t last_ns = 0;
    std::uint64_t suppressed = 0;
  };
  std::int64_t interval_ns_;
  std::array<Slot, kMaxReasons> slots_{};
  std::uint64_t suppressed_total_ = 0;
};

// "; N more suppressed" for a Gate that suppressed lines before it, else "".
std::string suppressed_note(const LogLimiter::Gate& gate);

}  // namespace hystloop
