#include "summary_json.hpp"

#include <cmath>

#include "json_writer.hpp"

namespace hystloop::report {

namespace {

void write_params(JsonWriter& json, std::string_view name, const std::optional<MemParams>& p) {
  json.key(name);
  if (!p) {
    json.null();
    return;
  }
  json.begin_object().field("version", p->version).field("c1", p->c1).field("c2", p->c2).field("c3", p->c3).end_object();
}

std::optional<double> finite_or_null(double v) { return std::isfinite(v) ? std::optional<double>(v) : std::nullopt; }

}  // namespace

std::string summary_json(const ReportMetrics& m, const ReportOptions& options,
                         const std::vector<std::filesystem::path>& files) {
  JsonWriter json;
  json.begin_object();
  json.field("tool", "hystloop-report");
  json.key("files").begin_array();
  for (const auto& file : files) json.value(file.string());
  json.end_array();
  json.field("time_axis",
             "t_s = LCM event-log timestamp minus that of the first sensor tick [s]; the log's timestamps are the "
             "logger's receive times; tick i of a sensor block of n received at R is dated R - (n - 1 - i) * dt_s");
  json.field("error_definition", "e = y_ref_m - y_m of each HX_SENSOR tick with a finite y_ref_m");
  json.key("range").begin_object();
  json.field("from_s", finite_or_null(options.lower_s()));
  json.field("to_s", finite_or_null(options.upper_s()));
  json.field("skip_initial_s", options.skip_initial_s);
  json.end_object();

  json.field("duration_s", m.duration_s);
  json.field("samples", m.samples);
  json.field("tracking_samples", m.tracking_samples);
  json.field("rms_error_m", m.rms_error_m);
  json.field("max_abs_error_m", m.max_abs_error_m);
  json.field("rms_error_first_5s_m", m.rms_error_first_5s_m);
  json.field("rms_error_last_5s_m", m.rms_error_last_5s_m);
  json.key("per_second").begin_array();
  for (const auto& bin : m.per_second) {
    json.begin_object()
        .field("t_s", bin.t_s)
        .field("rms_error_m", bin.rms_error_m)
        .field("tracking_samples", bin.tracking_samples)
        .field("params_version", bin.params_version)
        .end_object();
  }
  json.end_array();

  json.field("armed_samples", m.armed_samples);
  json.field("late_samples", m.late_samples);
  json.field("late_command_fraction", m.late_command_fraction);
  json.field("late_tick_fraction", m.late_command_fraction);

  json.field("tick_period_s", m.tick_period_s);
  json.field("sensor_blocks", m.sensor_blocks);
  json.field("armed_blocks", m.armed_blocks);
  json.field("buffer_min_depth_ticks", m.buffer_min_depth_ticks);

  json.field("run_ahead_definition",
             "per HX_COMMAND block: its first tick (seq) minus the last sensor tick the compensator had (sample_seq), "
             "in ticks; blocks without a sample_seq are left out");
  json.field("run_ahead_blocks", m.run_ahead_ticks.size());
  json.field("run_ahead_min_ticks", m.run_ahead_min_ticks);
  json.field("run_ahead_p01_ticks", m.run_ahead_p01_ticks);
  json.field("run_ahead_p50_ticks", m.run_ahead_p50_ticks);
  json.field("run_ahead_max_ticks", m.run_ahead_max_ticks);

  json.field("watchdog_trips", m.watchdog_trips);
  json.field("watchdog_trips_source", m.watchdog_trips_source);

  json.field("commands_rejected", m.commands_rejected);
  json.field("commands_rejected_source", m.commands_rejected_source);
  json.key("commands_rejected_counters").begin_object();
  for (const auto& [name, value] : m.commands_rejected_counters) json.field(name, value);
  json.end_object();

  json.key("params_history").begin_array();
  for (const auto& p : m.params_history) {
    json.begin_object()
        .field("t_s", p.t_s)
        .field("version", p.version)
        .field("c1", p.c1)
        .field("c2", p.c2)
        .field("c3", p.c3)
        .field("residual_m", p.residual_m)
        .field("valid", p.valid)
        .end_object();
  }
  json.end_array();
  write_params(json, "params_initial", m.params_initial);
  write_params(json, "params_final", m.params_final);
  json.field("params_updates", m.params_updates);

  json.field("logger_gaps", m.logger_gaps);
  json.field("logger_gaps_source", m.logger_gaps_source);
  json.field("seq_gaps", m.seq_gaps);
  json.field("missing_samples", m.missing_samples);

  json.field("events", m.events);
  json.field("undecodable_events", m.undecodable);
  json.key("channels").begin_object();
  for (const auto& [name, count] : m.channels) json.field(name, count);
  json.end_object();
  json.field("messages_per_s_definition", "events of each channel received between the first and the last sensor "
                                          "tick of the range, divided by duration_s");
  json.key("messages_per_s").begin_object();
  for (const auto& [name, rate] : m.messages_per_s) json.field(name, rate);
  json.end_object();
  json.field("cpu_fraction_definition", "per process: cpu_user_us + cpu_system_us of its HX_STATUS counters, last "
                                        "minus first status in the range, over the wall time between them (1 = one "
                                        "core busy)");
  json.key("cpu_fraction").begin_object();
  for (const auto& [process, fraction] : m.cpu_fraction) json.field(process, fraction);
  json.end_object();
  json.end_object();
  return json.str();
}

}  // namespace hystloop::report
