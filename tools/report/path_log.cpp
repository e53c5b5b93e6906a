#include "path_log.hpp"

#include <algorithm>
#include <set>
#include <unordered_map>

#include "decode.hpp"
#include "lcm/blocks.hpp"
#include "lcm/scan_message.hpp"
#include "lcm/status_counters.hpp"
#include "log_reader.hpp"

namespace hystloop::report {

LoggedPath logged_path(const scan_t& msg, std::int64_t recv_utime) {
  LoggedPath p;
  p.recv_utime = recv_utime;
  p.version = msg.version;
  p.blend_s = msg.blend_s;
  p.decouple = msg.decouple != 0;
  p.start_utime = msg.start_utime;
  // Logged, so it passed check_message: a raster or a Lissajous figure.
  p.path = scan_path_of(msg);
  return p;
}

PathEvents read_path_events(const std::vector<std::filesystem::path>& files, const ChannelNames& channels,
                            const std::string& compensator_process) {
  PathEvents out;
  std::set<std::int64_t> versions;
  scan_t scan;
  service_status_t status;
  for_each_event(files, [&](const lcm::LogEvent& event) {
    if (event.channel == channels.scan) {
      if (!decode_checked(event, scan) || !versions.insert(scan.version).second) return;
      out.paths.push_back(logged_path(scan, event.timestamp));
    } else if (event.channel == channels.status) {
      if (!decode_checked(event, status) || status.process != compensator_process) return;
      ScanCompensatorStatus s;
      s.recv_utime = event.timestamp;
      s.detail = status.detail;
      s.trajectory_version = find_counter(status, "trajectory_version");
      s.trajectory_refused_version = find_counter(status, "trajectory_refused_version");
      out.compensator.push_back(std::move(s));
    }
  });
  return out;
}

std::vector<PathTick> read_path_ticks(const std::vector<std::filesystem::path>& files, const ChannelNames& channels,
                                      const std::vector<LoopWindow>& windows) {
  std::vector<PathTick> ticks;
  sensor_block_t sensor;
  sim_truth_t truth;
  // A block is kept whole when any of its ticks is in a window (its truth is then matched whole).
  const auto overlaps = [&](double from_s, double to_s) {
    return std::any_of(windows.begin(), windows.end(),
                       [&](const LoopWindow& w) { return from_s <= w.to_s && to_s >= w.from_s; });
  };
  struct KeptBlock {
    std::size_t first = 0;  // index in `ticks` of its first tick
    std::size_t n = 0;      // its ticks
    std::size_t axes = 1;
  };
  // A truth block follows its sensor block; one that comes first waits for it (a reordering
  // network). A truth block of a block already seen but not kept is dropped at once, so that
  // nothing waits for good.
  std::unordered_map<std::int64_t, KeptBlock> kept;  // by the block's seq
  std::unordered_map<std::int64_t, sim_truth_t> truth_waiting;
  std::int64_t last_sensor_seq = -1;
  const auto apply_truth = [&](const KeptBlock& b, const sim_truth_t& m) {
    if (ticks_of(m) != b.n || axes_of(m) != b.axes) return;  // not this block's truth
    for (std::size_t i = 0; i < b.n; ++i) {
      for (std::size_t a = 0; a < b.axes; ++a) ticks[b.first + i].y_true_m[a] = m.y_true_m[i * b.axes + a];
    }
  };
  for_each_event(files, [&](const lcm::LogEvent& event) {
    if (event.channel == channels.sensor) {
      if (!decode_checked(event, sensor)) return;
      last_sensor_seq = std::max(last_sensor_seq, sensor.seq);
      const std::size_t n = ticks_of(sensor);
      if (!overlaps(static_cast<double>(sensor.seq) * sensor.dt_s,
                    static_cast<double>(last_seq(sensor)) * sensor.dt_s)) {
        return;
      }
      const KeptBlock block{ticks.size(), n, axes_of(sensor)};
      for (std::size_t i = 0; i < n; ++i) {
        PathTick t;
        t.seq = sensor.seq + static_cast<std::int64_t>(i);
        t.dt_s = sensor.dt_s;
        t.recv_utime = tick_recv_utime(event.timestamp, sensor.n_ticks, i, sensor.dt_s);
        t.axes = static_cast<int>(block.axes);
        for (std::size_t a = 0; a < block.axes; ++a) {
          const SensorTick k = sensor_tick(sensor, i, a);
          t.y_ref_m[a] = k.y_ref_m;
          t.y_m[a] = k.y_m;
          t.safe = t.safe || (k.flags & sensor_block_t::SAFE_STATE) != 0;
        }
        ticks.push_back(t);
      }
      kept[sensor.seq] = block;
      if (const auto w = truth_waiting.find(sensor.seq); w != truth_waiting.end()) {
        apply_truth(block, w->second);
        truth_waiting.erase(w);
      }
    } else if (event.channel == channels.sim_truth) {
      if (!decode_checked(event, truth)) return;
      if (const auto b = kept.find(truth.seq); b != kept.end()) {
        apply_truth(b->second, truth);
      } else if (truth.seq > last_sensor_seq) {
        truth_waiting[truth.seq] = truth;
      }
    }
  });
  return ticks;
}

}  // namespace hystloop::report
