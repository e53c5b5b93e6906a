#include "log_reader.hpp"

#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>
#include <unordered_map>
#include <utility>
#include <vector>

#include "core/errors.hpp"
#include "decode.hpp"
#include "event_file.hpp"
#include "lcm/blocks.hpp"
#include "models/axis_coupling.hpp"
#include "models/model_set.hpp"
#include "record/record_auth.hpp"

namespace hystloop::report {

namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
}  // namespace

std::vector<LogFileScan> for_each_event(const std::vector<std::filesystem::path>& files,
                                        const std::function<void(const lcm::LogEvent&)>& visit,
                                        std::shared_ptr<const RigAuth> auth) {
  std::vector<LogFileScan> scans;
  RecordCheck check(std::move(auth));  // one for the recording: a replay across its files is caught
  for (const auto& file : files) {
    EventFileReader reader(file);
    while (const lcm::LogEvent* event = reader.next()) {
      if (check.admit(event->channel, event->data, static_cast<std::size_t>(event->datalen), event->timestamp)) {
        visit(*event);
      }
    }
    LogFileScan scan = reader.scan();
    scan.recorded_keyed = check.marked_keyed();
    scan.unverified_left_out = check.left_out();
    scan.signature_notes = check.take_notes();
    scans.push_back(std::move(scan));
  }
  return scans;
}

std::string channel_list(const std::map<std::string, std::uint64_t>& counts) {
  std::string out;
  for (const auto& [channel, n] : counts) out += (out.empty() ? "" : ", ") + channel;
  return out.empty() ? "none" : out;
}

std::string resolve_channel(const std::string& name, const std::map<std::string, std::uint64_t>& counts,
                            const std::string& prefix, const char* option) {
  if (counts.count(name) != 0) return name;
  if (counts.count(prefix + name) != 0) return prefix + name;
  throw ParameterError(option, "no channel '" + name + "' in the log (channels: " + channel_list(counts) + ")");
}

std::vector<std::string> describe_scan_problems(const std::vector<LogFileScan>& scans) {
  std::vector<std::string> out;
  for (const auto& s : scans) {
    if (s.bytes == 0) {
      out.push_back(s.file + ": empty (0 bytes)");
    } else if (s.events == 0) {
      out.push_back(s.file + ": no LCM event in its " + std::to_string(s.bytes) + " bytes (not an LCM event log?)");
    } else {
      if (s.skipped_bytes > 0) {
        out.push_back(s.file + ": " + std::to_string(s.skipped_bytes) +
                      " bytes between events are not events (corrupt or torn writes) and were skipped");
      }
      if (s.trailing_bytes > 0) {
        out.push_back(s.file + ": the last " + std::to_string(s.trailing_bytes) + " bytes after event " +
                      std::to_string(s.events) + " are not a complete event (truncated log?)");
      }
    }
    for (const auto& note : s.signature_notes) out.push_back(s.file + ": " + note);
  }
  return out;
}

std::int64_t tick_recv_utime(std::int64_t block_recv_utime, std::int32_t n_ticks, std::size_t i, double dt_s) noexcept {
  const double back_us =
      static_cast<double>(static_cast<std::int64_t>(n_ticks) - 1 - static_cast<std::int64_t>(i)) * dt_s * 1e6;
  return block_recv_utime - static_cast<std::int64_t>(std::llround(back_us));
}

std::int64_t log_time_zero_utime(const std::vector<std::filesystem::path>& files, const std::string& sensor_channel,
                                 std::shared_ptr<const RigAuth> auth) {
  std::optional<std::int64_t> first_event;
  sensor_block_t block;
  RecordCheck check(std::move(auth));  // a block the rig refused does not set the time axis either
  for (const auto& file : files) {
    EventFileReader reader(file);
    while (const lcm::LogEvent* e = reader.next()) {
      if (!check.admit(e->channel, e->data, static_cast<std::size_t>(e->datalen), e->timestamp)) continue;
      if (!first_event) first_event = e->timestamp;
      if (e->channel == sensor_channel && decode_checked(*e, block)) {
        return tick_recv_utime(e->timestamp, block.n_ticks, 0, block.dt_s);
      }
    }
  }
  return first_event.value_or(0);
}

std::string axes_text(int axes) {
  std::string names;
  for (int a = 0; a < axes; ++a) {
    names += std::string(a == 0 ? "" : a + 1 == axes ? " and " : ", ") + std::string(axis_name(a));
  }
  return std::to_string(axes) + (axes == 1 ? " axis (" : " axes (") + names + ")";
}

void require_axis(const RunData& run, const std::string& sensor_channel) {
  if (run.sensor_blocks_by_axes.empty()) return;
  const int most = run.sensor_blocks_by_axes.rbegin()->first;
  if (run.axis < most) return;
  throw ParameterError("--axis", "the log's " + sensor_channel + " blocks carry " +
                                     (run.sensor_blocks_by_axes.size() > 1 ? "at most " : "") + axes_text(most) +
                                     ", not " + std::string(axis_name(run.axis)));
}

RunData read_logs(const std::vector<std::filesystem::path>& files, const ChannelNames& channels, int axis,
                  std::shared_ptr<const RigAuth> auth) {
  RunData run;
  run.axis = axis;
  run.signatures_verified = auth != nullptr;
  const auto a = static_cast<std::size_t>(axis);
  sensor_block_t sensor;
  command_block_t command;
  mem_params_t params;
  model_params_t model;
  service_status_t status;
  control_t control;
  sim_truth_t truth;
  // A truth block is matched to the sensor block with its seq and n_ticks (the bridge sends it
  // right after; kept the other way round too, should the network reorder them).
  struct BlockSamples {
    std::size_t first = 0;  // index in run.samples of the block's first tick
    std::size_t n = 0;      // its ticks
  };
  std::unordered_map<std::int64_t, BlockSamples> sensor_blocks;  // by the block's seq
  std::unordered_map<std::int64_t, std::vector<double>> truth_waiting;
  const auto apply_truth = [&](const BlockSamples& b, const std::vector<double>& y) {
    if (y.size() != b.n) return;  // not this block's truth
    for (std::size_t i = 0; i < b.n; ++i) run.samples[b.first + i].y_true_m = y[i];
    run.truth_ticks += b.n;
  };
  const auto visit = [&](const lcm::LogEvent& event) {
    ++run.events;
    ++run.channel_counts[event.channel];
    run.event_times[event.channel].push_back(event.timestamp);
    if (!run.first_event_utime) run.first_event_utime = event.timestamp;
    const std::int64_t t = event.timestamp;
    if (event.channel == channels.sensor) {
      if (!decode_checked(event, sensor)) return void(++run.undecodable);
      ++run.sensor_blocks_by_axes[static_cast<int>(axes_of(sensor))];
      if (a >= axes_of(sensor)) return void(++run.blocks_without_axis);
      bool armed = true;
      std::size_t i = 0;
      for_each_tick(
          sensor,
          [&](const SensorTick& k) {
            run.samples.push_back(
                {tick_recv_utime(t, sensor.n_ticks, i++, sensor.dt_s), k.seq, k.u_V, k.y_ref_m, k.y_m, k.flags});
            armed = armed && (k.flags & sensor_block_t::SAFE_STATE) == 0;
          },
          a);
      run.sensor_blocks.push_back({t, sensor.dt_s, sensor.buffer_depth_ticks, armed});
      const auto n = static_cast<std::size_t>(sensor.n_ticks);
      const BlockSamples block{run.samples.size() - n, n};
      sensor_blocks[sensor.seq] = block;
      if (const auto w = truth_waiting.find(sensor.seq); w != truth_waiting.end()) {
        apply_truth(block, w->second);
        truth_waiting.erase(w);
      }
    } else if (event.channel == channels.sim_truth) {
      if (!decode_checked(event, truth)) return void(++run.undecodable);
      if (const auto b = sensor_blocks.find(truth.seq); b != sensor_blocks.end()) {
        apply_truth(b->second, axis_truth(truth, a));
      } else {
        truth_waiting[truth.seq] = axis_truth(truth, a);
      }
    } else if (event.channel == channels.command) {
      if (!decode_checked(event, command)) return void(++run.undecodable);
      run.command_blocks.push_back({t, command.seq, command.sample_seq});
      if (a >= axes_of(command)) return;  // no command of this axis: its ticks' versions stay unknown
      for_each_tick(
          command, [&](const CommandTick& k) { run.command_versions.add(k.seq, k.params_version, k.mode); }, a);
    } else if (event.channel == channels.params) {
      if (!decode_checked(event, params)) return void(++run.undecodable);
      if (params.axis != axis) return;  // another axis's hysteresis
      run.params.push_back({t, params.version, params.c1, params.c2, params.c3, params.residual_m, params.valid != 0,
                            "mem", params.residual_m, false});
    } else if (event.channel == channels.model) {
      if (!decode_checked(event, model)) return void(++run.undecodable);
      if (model.axis != axis) return;
      const bool mem = model.kind == model_params_t::KIND_MEM;
      const std::optional<ModelKind> kind = model_kind_from_int(model.kind);
      run.params.push_back({t, model.version, mem ? model.mem_c1 : kNaN, mem ? model.mem_c2 : kNaN,
                            mem ? model.mem_c3 : kNaN, model.residual_m, model.valid != 0,
                            kind ? std::string(to_string(*kind)) : "unknown", model.heldout_rms_m, true});
    } else if (event.channel == channels.status) {
      if (!decode_checked(event, status)) return void(++run.undecodable);
      StatusRecord record{t, status.process, status.rejected, {}, status.utime, status.start_utime};
      for (std::size_t i = 0; i < status.counter_names.size(); ++i) {
        record.counters.emplace_back(status.counter_names[i], status.counter_values[i]);
      }
      run.statuses.push_back(std::move(record));
    } else if (event.channel == channels.control) {
      if (!decode_checked(event, control)) return void(++run.undecodable);
      if (control.command == control_t::DISARM || control.command == control_t::SHUTDOWN) {
        run.safe_requests.push_back({t, control.target});
      }
    }
  };
  run.files = for_each_event(files, visit, std::move(auth));
  return run;
}

}  // namespace hystloop::report
