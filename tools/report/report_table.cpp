#include "report_table.hpp"

#include <algorithm>
#include <cstdarg>
#include <cstdio>
#include <string>

#include "log_reader.hpp"
#include "models/axis_coupling.hpp"

namespace hystloop::report {

namespace {

std::string fmt(const char* format, ...) __attribute__((format(printf, 1, 2)));
std::string fmt(const char* format, ...) {
  char buf[512];
  va_list args;
  va_start(args, format);
  std::vsnprintf(buf, sizeof buf, format, args);
  va_end(args);
  return buf;
}

std::string nm(const std::optional<double>& metres) {
  return metres ? fmt("%.1f nm", *metres * 1e9) : std::string("--");
}

std::string ticks(const std::optional<double>& n) { return n ? fmt("%.0f", *n) : std::string("--"); }

// A count with where it came from: "3  (last bridge status: watchdog_trips)"; "--  (...)" without one.
std::string sourced(const std::optional<std::int64_t>& n, const std::string& source) {
  return (n ? fmt("%lld", static_cast<long long>(*n)) : std::string("--")) + "  (" + source + ")";
}

std::string params(const std::optional<MemParams>& p) {
  return p ? fmt("v%d (c1 %.4g, c2 %.4g, c3 %.4g)", p->version, p->c1, p->c2, p->c3) : std::string("--");
}

}  // namespace

std::string format_table(const ReportMetrics& m) {
  std::string out;
  auto row = [&out](const char* name, const std::string& value) { out += fmt("  %-22s %s\n", name, value.c_str()); };
  // Only a log of several axes names the one shown: a one-axis report reads as it always did.
  if (m.log_axes > 1)
    row("axis",
        fmt("%s  (the sensor blocks carry %s)", std::string(axis_name(m.axis)).c_str(), axes_text(m.log_axes).c_str()));
  row("duration",
      fmt("%.2f s, %zu ticks, %llu events", m.duration_s, m.samples, static_cast<unsigned long long>(m.events)));
  row("tracking RMS error", nm(m.rms_error_m) + fmt("  (%zu ticks with a reference)", m.tracking_samples));
  row("  first / last 5 s", nm(m.rms_error_first_5s_m) + " / " + nm(m.rms_error_last_5s_m));
  row("  max |error|", nm(m.max_abs_error_m));
  row("late commands", m.late_command_fraction ? fmt("%.4f %%  (%zu of %zu armed ticks)",
                                                     *m.late_command_fraction * 100.0, m.late_samples, m.armed_samples)
                                               : std::string("--  (no armed ticks)"));
  std::size_t worst_second = 0;
  for (const auto& bin : m.per_second) worst_second = std::max(worst_second, bin.clamped_samples);
  row("clamped ticks", fmt("%zu  (range %zu, slew %zu; at most %zu in a second)", m.clamped_samples,
                           m.clamped_range_samples, m.clamped_slew_samples, worst_second));
  row("buffer min depth", m.buffer_min_depth_ticks
                              ? fmt("%d ticks  (%zu armed of %zu sensor blocks)", *m.buffer_min_depth_ticks,
                                    m.armed_blocks, m.sensor_blocks)
                              : fmt("--  (%zu armed of %zu sensor blocks)", m.armed_blocks, m.sensor_blocks));
  row("run-ahead min/p1/p50", ticks(m.run_ahead_min_ticks) + " / " + ticks(m.run_ahead_p01_ticks) + " / " +
                                  ticks(m.run_ahead_p50_ticks) +
                                  fmt(" ticks  (n = %zu command blocks)", m.run_ahead_ticks.size()));
  row("watchdog trips", sourced(m.watchdog_trips, m.watchdog_trips_source));
  std::string cpu;
  for (const auto& [process, fraction] : m.cpu_fraction) {
    cpu +=
        (cpu.empty() ? "" : ", ") + process + " " + (fraction ? fmt("%.1f %%", *fraction * 100.0) : std::string("--"));
  }
  row("cpu", cpu.empty() ? std::string("--  (no status)") : cpu);
  row("commands rejected", sourced(m.commands_rejected, m.commands_rejected_source));
  row("params initial", params(m.params_initial));
  row("params final", params(m.params_final) + fmt("  (%zu updates)", m.params_updates));
  row("logger gaps", sourced(m.logger_gaps, m.logger_gaps_source) + fmt("; sensor seq: %lld gaps, %lld missing",
                                                                        static_cast<long long>(m.seq_gaps),
                                                                        static_cast<long long>(m.missing_samples)));
  if (m.undecodable > 0) row("undecodable events", fmt("%llu", static_cast<unsigned long long>(m.undecodable)));
  return out;
}

}  // namespace hystloop::report
