#include "ctl_watch.hpp"

#include <cmath>
#include <cstdio>

namespace hystloop::ctl {

std::optional<double> TickMatcher::on_command(std::int64_t seq, double y_ref_m) noexcept {
  if (seq < 0) return std::nullopt;
  Slot& sample = samples_[slot(seq)];
  if (sample.seq == seq) {
    sample.seq = -1;
    if (!std::isfinite(y_ref_m)) return std::nullopt;
    return sample.value - y_ref_m;
  }
  commands_[slot(seq)] = {seq, y_ref_m};
  return std::nullopt;
}

std::optional<double> TickMatcher::on_sample(std::int64_t seq, double y_m) noexcept {
  if (seq < 0) return std::nullopt;
  Slot& command = commands_[slot(seq)];
  if (command.seq == seq) {
    command.seq = -1;
    if (!std::isfinite(command.value)) return std::nullopt;
    return y_m - command.value;
  }
  samples_[slot(seq)] = {seq, y_m};
  return std::nullopt;
}

void WatchSecond::add_error(double e_m) noexcept {
  ++tracking;
  sum_sq_m2 += e_m * e_m;
  max_abs_m = std::max(max_abs_m, std::abs(e_m));
}

std::optional<double> WatchSecond::rms_m() const noexcept {
  if (tracking == 0) return std::nullopt;
  return std::sqrt(sum_sq_m2 / static_cast<double>(tracking));
}

std::string format_watch_line(const WatchLine& l) {
  char buf[320];
  std::string out;
  std::snprintf(buf, sizeof buf, "%5.0f s", l.elapsed_s);
  out += buf;
  if (const auto rms = l.second.rms_m()) {
    std::snprintf(buf, sizeof buf, "  rms %7.1f nm  max %7.1f nm", *rms * 1e9, l.second.max_abs_m * 1e9);
  } else {
    std::snprintf(buf, sizeof buf, "  rms %7s nm  max %7s nm", "--", "--");
  }
  out += buf;
  std::snprintf(buf, sizeof buf, "  ticks %6llu/%llu", static_cast<unsigned long long>(l.second.tracking),
                static_cast<unsigned long long>(l.second.samples));
  out += buf;
  out += l.params_in_use ? "  params v" + std::to_string(*l.params_in_use) : std::string("  params --");
  if (l.params_latest && l.params_latest != l.params_in_use) out += " (v" + std::to_string(*l.params_latest) + " published)";
  if (l.late_total) {
    std::snprintf(buf, sizeof buf, "  late %lld (+%lld)", static_cast<long long>(*l.late_total),
                  static_cast<long long>(l.late_delta.value_or(0)));
    out += buf;
  } else {
    out += "  late --";
  }
  if (l.latency_p99_us && std::isfinite(*l.latency_p99_us)) {
    std::snprintf(buf, sizeof buf, "  lat p99 %.0f us", *l.latency_p99_us);
    out += buf;
  } else {
    out += "  lat p99 --";
  }
  out += l.bridge_state.empty() ? "  bridge --" : "  bridge " + l.bridge_state;
  return out;
}

}  // namespace hystloop::ctl
