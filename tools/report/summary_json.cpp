#include "summary_json.hpp"

#include <cmath>
#include <optional>

#include <nlohmann/json.hpp>

#include "models/axis_coupling.hpp"
#include "path_output.hpp"

namespace hystloop::report {

namespace {

// Keys in the order they are set (readers and diffs see the layout the tool always wrote).
using Json = nlohmann::ordered_json;

// A missing or non-finite number is null; integers stay integers.
template <class T>
Json number_or_null(const T& v) {
  return Json(v);
}
Json number_or_null(double v) { return std::isfinite(v) ? Json(v) : Json(nullptr); }
template <class T>
Json number_or_null(const std::optional<T>& v) {
  return v ? number_or_null(*v) : Json(nullptr);
}

Json params_json(const std::optional<MemParams>& p) {
  if (!p) return nullptr;
  return Json{{"version", p->version}, {"c1", p->c1}, {"c2", p->c2}, {"c3", p->c3}};
}

Json params_history_json(const std::vector<ParamsPoint>& history) {
  Json out = Json::array();
  for (const auto& p : history) {
    out.push_back(Json{{"t_s", p.t_s},
                       {"version", p.version},
                       {"model", p.model},
                       {"model_change", p.model_change},
                       {"c1", number_or_null(p.c1)},
                       {"c2", number_or_null(p.c2)},
                       {"c3", number_or_null(p.c3)},
                       {"residual_m", number_or_null(p.residual_m)},
                       {"heldout_rms_m", number_or_null(p.heldout_rms_m)},
                       {"valid", p.valid}});
  }
  return out;
}

// Name -> value pairs (a map, or a vector of pairs) as an object.
template <class Map>
Json map_json(const Map& map) {
  Json out = Json::object();
  for (const auto& [name, value] : map) out[name] = number_or_null(value);
  return out;
}

// A count that has more than one possible origin, then "<key>_source": which one it came from.
void counted(Json& j, const std::string& key, const std::optional<std::int64_t>& count, const std::string& source) {
  j[key] = number_or_null(count);
  j[key + "_source"] = source;
}

}  // namespace

std::string summary_json(const ReportMetrics& m, const ReportOptions& options,
                         const std::vector<std::filesystem::path>& files, const std::vector<PathFigures>& paths) {
  Json j;
  j["tool"] = "hystloop-report";
  j["files"] = Json::array();
  for (const auto& file : files) j["files"].push_back(file.string());
  j["time_axis"] =
      "t_s = LCM event-log timestamp minus that of the first sensor tick [s]; the log's timestamps are the "
      "logger's receive times; tick i of a sensor block of n received at R is dated R - (n - 1 - i) * dt_s";
  j["axis"] = std::string(axis_name(m.axis));
  j["error_definition"] = "e = y_ref_m - y_m of each HX_SENSOR tick with a finite y_ref_m";
  j["range"] = Json{{"from_s", number_or_null(options.lower_s())},
                    {"to_s", number_or_null(options.upper_s())},
                    {"skip_initial_s", options.skip_initial_s}};

  j["duration_s"] = m.duration_s;
  j["samples"] = m.samples;
  j["tracking_samples"] = m.tracking_samples;
  j["rms_error_m"] = number_or_null(m.rms_error_m);
  j["max_abs_error_m"] = number_or_null(m.max_abs_error_m);
  j["rms_error_first_5s_m"] = number_or_null(m.rms_error_first_5s_m);
  j["rms_error_last_5s_m"] = number_or_null(m.rms_error_last_5s_m);
  Json per_second = Json::array();
  Json rms_per_second = Json::array();  // the same bins' RMS alone: a plain series
  Json clamped_per_second = Json::array();
  for (const auto& bin : m.per_second) {
    per_second.push_back(Json{{"t_s", bin.t_s},
                              {"rms_error_m", number_or_null(bin.rms_error_m)},
                              {"tracking_samples", bin.tracking_samples},
                              {"params_version", bin.params_version},
                              {"clamped_ticks", bin.clamped_samples}});
    rms_per_second.push_back(number_or_null(bin.rms_error_m));
    clamped_per_second.push_back(bin.clamped_samples);
  }
  j["per_second"] = std::move(per_second);
  j["rms_per_second_m"] = std::move(rms_per_second);
  j["clamped_definition"] =
      "HX_SENSOR ticks flagged SATURATED (clamped to the actuator's range) or SLEW_LIMITED; either counts a tick "
      "clamped by both once; clamped_per_second: either, per one-second bin of per_second";
  j["clamped_ticks"] =
      Json{{"range", m.clamped_range_samples}, {"slew", m.clamped_slew_samples}, {"either", m.clamped_samples}};
  j["clamped_per_second"] = std::move(clamped_per_second);

  j["armed_samples"] = m.armed_samples;
  j["late_samples"] = m.late_samples;
  j["late_command_fraction"] = number_or_null(m.late_command_fraction);
  j["late_tick_fraction"] = number_or_null(m.late_command_fraction);

  j["tick_period_s"] = number_or_null(m.tick_period_s);
  j["sensor_blocks"] = m.sensor_blocks;
  j["armed_blocks"] = m.armed_blocks;
  j["buffer_min_depth_ticks"] = number_or_null(m.buffer_min_depth_ticks);

  j["run_ahead_definition"] =
      "per HX_COMMAND block: its first tick (seq) minus the last sensor tick the compensator had (sample_seq), "
      "in ticks; blocks without a sample_seq are left out";
  j["run_ahead_blocks"] = m.run_ahead_ticks.size();
  j["run_ahead_min_ticks"] = number_or_null(m.run_ahead_min_ticks);
  j["run_ahead_p01_ticks"] = number_or_null(m.run_ahead_p01_ticks);
  j["run_ahead_p50_ticks"] = number_or_null(m.run_ahead_p50_ticks);
  j["run_ahead_max_ticks"] = number_or_null(m.run_ahead_max_ticks);

  counted(j, "watchdog_trips", m.watchdog_trips, m.watchdog_trips_source);
  counted(j, "commands_rejected", m.commands_rejected, m.commands_rejected_source);
  j["commands_rejected_counters"] = map_json(m.commands_rejected_counters);

  j["params_history"] = params_history_json(m.params_history);
  j["params_initial"] = params_json(m.params_initial);
  j["params_final"] = params_json(m.params_final);
  j["params_updates"] = m.params_updates;

  counted(j, "logger_gaps", m.logger_gaps, m.logger_gaps_source);
  j["seq_gaps"] = m.seq_gaps;
  j["missing_samples"] = m.missing_samples;

  j["events"] = m.events;
  j["undecodable_events"] = m.undecodable;
  j["recorded_keyed"] = m.recorded_keyed;
  j["signatures_verified"] = m.signatures_verified;
  j["unverified_events_left_out"] = m.unverified_left_out;
  j["channels"] = map_json(m.channels);
  j["messages_per_s_definition"] =
      "events of each channel received between the first and the last sensor tick of the range, divided by "
      "duration_s";
  j["messages_per_s"] = map_json(m.messages_per_s);
  j["cpu_fraction_definition"] =
      "per process: cpu_user_us + cpu_system_us of its HX_STATUS counters, last minus first status in the range, "
      "over the wall time between them (1 = one core busy)";
  j["cpu_fraction"] = map_json(m.cpu_fraction);
  if (!paths.empty()) j["scan_paths"] = paths_json(paths);
  // Two-space indentation as before; invalid UTF-8 in a file name is replaced, not thrown.
  return j.dump(2, ' ', false, Json::error_handler_t::replace) + "\n";
}

}  // namespace hystloop::report
