#include "status_figures.hpp"

#include <array>
#include <map>
#include <optional>
#include <string_view>

namespace hystloop::report {

namespace {

std::string_view leaf(std::string_view name) {
  const auto dot = name.rfind('.');
  return dot == std::string_view::npos ? name : name.substr(dot + 1);
}

std::string_view endpoint(std::string_view name) {
  const auto dot = name.rfind('.');
  return dot == std::string_view::npos ? std::string_view{} : name.substr(0, dot);
}

// A bridge counter counts as a rejected command when its leaf is "rejected*" or "stale"
// (DESIGN.md: stale commands are rejected) and it is not another endpoint's counter.
bool is_command_reject_counter(std::string_view name) {
  const std::string_view l = leaf(name);
  const std::string_view e = endpoint(name);
  const bool reject = l.starts_with("rejected") || l == "stale";
  const bool commands =
      e.empty() || e.find("command") != std::string_view::npos || e.find("cmd") != std::string_view::npos;
  return reject && commands;
}

std::optional<std::int64_t> report_cpu_us(const StatusRecord& s) {
  const auto user = s.counter("cpu_user_us");
  const auto system = s.counter("cpu_system_us");
  if (!user || !system) return std::nullopt;
  return *user + *system;
}

// The last status of `process` received at or before upper_utime; nullptr if none.
const StatusRecord* last_status(const RunData& run, const std::string& process, std::int64_t upper_utime) {
  const StatusRecord* last = nullptr;
  for (const auto& status : run.statuses) {
    if (status.process == process && status.recv_utime <= upper_utime) last = &status;
  }
  return last;
}

}  // namespace

void fill_commands_rejected(const RunData& run, const ReportOptions& options, std::int64_t upper_utime,
                            ReportMetrics& m) {
  const StatusRecord* bridge = last_status(run, options.bridge_process, upper_utime);
  if (bridge == nullptr) {
    m.commands_rejected_source = "no status of process '" + options.bridge_process + "' in the log";
    return;
  }
  std::int64_t sum = 0;
  for (const auto& [name, value] : bridge->counters) {
    if (!is_command_reject_counter(name)) continue;
    sum += value;
    m.commands_rejected_counters.emplace_back(name, value);
  }
  if (!m.commands_rejected_counters.empty()) {
    m.commands_rejected = sum;
    m.commands_rejected_source = "last " + options.bridge_process + " status: sum of its command reject counters";
  } else {
    m.commands_rejected = bridge->rejected;
    m.commands_rejected_source = "last " + options.bridge_process + " status: 'rejected' (no command reject counters)";
  }
}

void fill_logger_gaps(const RunData& run, const ReportOptions& options, std::int64_t upper_utime, ReportMetrics& m) {
  if (const StatusRecord* logger = last_status(run, options.logger_process, upper_utime)) {
    // Most specific name first: "gaps", then "*gaps", then anything with "gap".
    const std::array<bool (*)(std::string_view), 3> tiers{
        [](std::string_view l) { return l == "gaps"; }, [](std::string_view l) { return l.ends_with("gaps"); },
        [](std::string_view l) { return l.find("gap") != std::string_view::npos; }};
    for (const auto& matches : tiers) {
      std::int64_t sum = 0;
      std::string names;
      for (const auto& [name, value] : logger->counters) {
        if (!matches(leaf(name))) continue;
        sum += value;
        names += (names.empty() ? "" : "+") + name;
      }
      if (!names.empty()) {
        m.logger_gaps = sum;
        m.logger_gaps_source = "last " + options.logger_process + " status: " + names;
        return;
      }
    }
  }
  m.logger_gaps = m.seq_gaps;
  m.logger_gaps_source = "sensor seq (no gap counter from '" + options.logger_process + "')";
}

void fill_watchdog_trips(const RunData& run, const ReportOptions& options, std::int64_t upper_utime,
                         std::int64_t transitions, ReportMetrics& m) {
  if (const StatusRecord* bridge = last_status(run, options.bridge_process, upper_utime)) {
    if (const auto trips = bridge->counter("watchdog_trips")) {
      m.watchdog_trips = *trips;
      m.watchdog_trips_source = "last " + options.bridge_process + " status: watchdog_trips";
      return;
    }
  }
  m.watchdog_trips = transitions;
  m.watchdog_trips_source =
      "sensor ticks: armed -> SAFE_STATE transitions not preceded by a DISARM/SHUTDOWN request "
      "(no watchdog_trips counter from '" +
      options.bridge_process + "')";
}

void fill_cpu_fraction(const RunData& run, std::int64_t lower_utime, std::int64_t upper_utime, ReportMetrics& m) {
  struct Accumulator {
    const StatusRecord* first = nullptr;  // of the current segment
    const StatusRecord* last = nullptr;
    std::int64_t cpu_us = 0;  // of the closed segments
    std::int64_t wall_us = 0;
    void close() {
      if (first != nullptr && last != first) {
        cpu_us += *report_cpu_us(*last) - *report_cpu_us(*first);
        wall_us += last->utime - first->utime;
      }
      first = last = nullptr;
    }
  };
  std::map<std::string, Accumulator> by_process;
  for (const auto& s : run.statuses) {
    if (s.recv_utime < lower_utime || s.recv_utime > upper_utime) continue;
    Accumulator& a = by_process[s.process];
    const auto cpu = report_cpu_us(s);
    if (!cpu) continue;
    if (a.last != nullptr &&
        (s.start_utime != a.last->start_utime || *cpu < *report_cpu_us(*a.last) || s.utime < a.last->utime)) {
      a.close();  // restarted, counters reset, or a clock step: a new segment
    }
    if (a.first == nullptr) a.first = &s;
    a.last = &s;
  }
  for (auto& [process, a] : by_process) {
    a.close();
    m.cpu_fraction[process] =
        a.wall_us > 0 ? std::optional<double>(static_cast<double>(a.cpu_us) / static_cast<double>(a.wall_us))
                      : std::nullopt;
  }
}

}  // namespace hystloop::report
