#include "log_reader.hpp"

#include <stdexcept>

#include "decode.hpp"

namespace hystloop::report {

void for_each_event(const std::vector<std::filesystem::path>& files,
                    const std::function<void(const lcm::LogEvent&)>& visit) {
  for (const auto& file : files) {
    if (!std::filesystem::is_regular_file(file)) throw std::runtime_error(file.string() + ": no such log file");
    lcm::LogFile log(file.string(), "r");
    if (!log.good()) throw std::runtime_error(file.string() + ": cannot open as an LCM event log");
    while (const lcm::LogEvent* event = log.readNextEvent()) visit(*event);
  }
}

RunData read_logs(const std::vector<std::filesystem::path>& files, const ChannelNames& channels) {
  RunData run;
  sensor_sample_t sample;
  actuator_command_t command;
  mem_params_t params;
  service_status_t status;
  for_each_event(files, [&](const lcm::LogEvent& event) {
    ++run.events;
    ++run.channel_counts[event.channel];
    if (!run.first_event_utime) run.first_event_utime = event.timestamp;
    const std::int64_t t = event.timestamp;
    if (event.channel == channels.sensor) {
      if (!decode_checked(event, sample)) return void(++run.undecodable);
      run.samples.push_back({t, sample.seq, sample.u_V, sample.y_m, sample.flags});
    } else if (event.channel == channels.command) {
      if (!decode_checked(event, command)) return void(++run.undecodable);
      run.commands.push_back({t, command.seq, command.sample_seq, command.u_V, command.y_ref_m, command.params_version});
    } else if (event.channel == channels.params) {
      if (!decode_checked(event, params)) return void(++run.undecodable);
      run.params.push_back({t, params.version, params.c1, params.c2, params.c3, params.residual_m, params.valid != 0});
    } else if (event.channel == channels.status) {
      if (!decode_checked(event, status)) return void(++run.undecodable);
      StatusRecord record{t, status.process, status.state, status.late, status.rejected, {}};
      for (std::size_t i = 0; i < status.counter_names.size(); ++i) {
        record.counters.emplace_back(status.counter_names[i], status.counter_values[i]);
      }
      run.statuses.push_back(std::move(record));
    }
  });
  return run;
}

}  // namespace hystloop::report
