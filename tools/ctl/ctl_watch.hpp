#pragma once
// `hystloop-ctl watch`: the tracking error of the running loop, per second. A tick's
// error needs two messages that arrive in either order: the command meant for tick k
// (its y_ref) and the sample of tick k (its y). TickMatcher pairs them by seq in fixed
// rings (no allocation per message; a half that waits longer than kSlots ticks is
// overwritten and forgotten).

#include <array>
#include <cstdint>
#include <optional>
#include <string>

namespace hystloop::ctl {

class TickMatcher {
 public:
  static constexpr std::size_t kSlots = std::size_t{1} << 16;  // 6.5 s at 10 kHz

  // Each returns e = y - y_ref when this message completes a tick with a finite y_ref.
  std::optional<double> on_command(std::int64_t seq, double y_ref_m) noexcept;
  std::optional<double> on_sample(std::int64_t seq, double y_m) noexcept;

 private:
  struct Slot {
    std::int64_t seq = -1;
    double value = 0.0;
  };
  static std::size_t slot(std::int64_t seq) noexcept { return static_cast<std::size_t>(seq) % kSlots; }
  std::array<Slot, kSlots> commands_{};
  std::array<Slot, kSlots> samples_{};
};

// What one second of watching saw.
struct WatchSecond {
  std::uint64_t samples = 0;
  std::uint64_t commands = 0;
  std::uint64_t tracking = 0;  // matched ticks with a reference
  double sum_sq_m2 = 0.0;
  double max_abs_m = 0.0;

  void add_error(double e_m) noexcept;
  std::optional<double> rms_m() const noexcept;
};

struct WatchLine {
  double elapsed_s = 0.0;
  WatchSecond second;
  std::optional<std::int32_t> params_in_use;   // from the commands
  std::optional<std::int32_t> params_latest;   // last HX_PARAMS version seen
  std::optional<std::int64_t> late_total;      // bridge status
  std::optional<std::int64_t> late_delta;      // since the previous bridge report
  std::optional<double> latency_p99_us;        // bridge status
  std::string bridge_state;                    // "" when no bridge status yet
};

// " 12 s  rms   27.9 nm  max   80.1 nm  ticks 10000  params v3  late 0 (+0)  lat p99 120 us  bridge HEALTHY"
std::string format_watch_line(const WatchLine& line);

}  // namespace hystloop::ctl
