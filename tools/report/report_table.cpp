#include "report_table.hpp"

#include <cstdarg>
#include <cstdio>

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

std::string us(const std::optional<double>& micros) { return micros ? fmt("%.1f us", *micros) : std::string("--"); }

std::string params(const std::optional<MemParams>& p) {
  return p ? fmt("v%d (c1 %.4g, c2 %.4g, c3 %.4g)", p->version, p->c1, p->c2, p->c3) : std::string("--");
}

}  // namespace

std::string format_table(const ReportMetrics& m) {
  std::string out;
  auto row = [&out](const char* name, const std::string& value) { out += fmt("  %-22s %s\n", name, value.c_str()); };
  row("duration", fmt("%.2f s, %zu samples, %llu events", m.duration_s, m.samples,
                      static_cast<unsigned long long>(m.events)));
  row("tracking RMS error", nm(m.rms_error_m) + fmt("  (%zu ticks with a reference)", m.tracking_samples));
  row("  first / last 5 s", nm(m.rms_error_first_5s_m) + " / " + nm(m.rms_error_last_5s_m));
  row("  max |error|", nm(m.max_abs_error_m));
  row("late commands", m.late_command_fraction ? fmt("%.4f %%  (%zu of %zu armed samples)", *m.late_command_fraction * 100.0,
                                                     m.late_samples, m.armed_samples)
                                               : std::string("--  (no armed samples)"));
  row("latency p50/p99/max", us(m.latency_p50_us) + " / " + us(m.latency_p99_us) + " / " + us(m.latency_max_us) +
                                 fmt("  (n = %zu)", m.latencies_us.size()));
  row("commands rejected", m.commands_rejected ? fmt("%lld", static_cast<long long>(*m.commands_rejected)) + "  (" +
                                                     m.commands_rejected_source + ")"
                                               : "--  (" + m.commands_rejected_source + ")");
  row("params initial", params(m.params_initial));
  row("params final", params(m.params_final) + fmt("  (%zu updates)", m.params_updates));
  row("logger gaps", (m.logger_gaps ? fmt("%lld", static_cast<long long>(*m.logger_gaps)) : std::string("--")) + "  (" +
                         m.logger_gaps_source + ")" +
                         fmt("; sensor seq: %lld gaps, %lld missing", static_cast<long long>(m.seq_gaps),
                             static_cast<long long>(m.missing_samples)));
  if (m.undecodable > 0) row("undecodable events", fmt("%llu", static_cast<unsigned long long>(m.undecodable)));
  return out;
}

}  // namespace hystloop::report
