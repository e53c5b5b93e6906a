// hystloop_python_banning_log OUT.lcmlog: a log of a short Banning series for test_banning, recorded
// as tools/identify/tests/identify_series_test.cpp records it (no faults): hystloop-ctl's requests
// (ctl::banning_series), run by the real Compensator against the simulated Banning stage tick by
// tick, logged as the logger would (HX_CONTROL, HX_COMMAND, HX_SENSOR) with lcm::LogFile.
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "ctl_series.hpp"
#include "hystloop/command_block_t.hpp"
#include "hystloop/control_t.hpp"
#include "hystloop/sensor_block_t.hpp"
#include "lcm/blocks.hpp"
#include "lcm/message_storage.hpp"
#include "loop/compensator.hpp"
#include "loop/simulated_stage.hpp"

namespace hystloop {
namespace {

constexpr std::int64_t kFirstSeq = 5000;
constexpr std::int64_t kRequestTick = kFirstSeq + 300;
constexpr std::int64_t kUtime0 = 1'700'000'000'000'000;
constexpr std::int64_t kBlockTicks = 10;

template <class T>
std::vector<std::uint8_t> encoded(const T& msg) {
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(msg.getEncodedSize()));
  msg.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  return bytes;
}

bool write_event(lcm::LogFile& log, std::int64_t& eventnum, std::int64_t utime, const std::string& channel,
                 std::vector<std::uint8_t> bytes) {
  lcm::LogEvent ev;
  ev.eventnum = eventnum++;
  ev.timestamp = utime;
  ev.channel = channel;
  ev.datalen = static_cast<std::int32_t>(bytes.size());
  ev.data = bytes.data();
  return log.writeEvent(&ev) == 0;
}

int record(const std::string& path) {
  BanningPlanOptions plan;
  plan.offsets_V = {-60.0, 60.0};
  plan.small_amplitudes_V = {2.0};
  plan.amplitudes_V = {50.0, 120.0};
  plan.hysteresis_frequency_Hz = 5.0;
  plan.frequencies_Hz = {300.0, 1200.0, 1700.0, 2400.0};
  const std::vector<ctl::SeriesStep> steps = ctl::banning_series(plan);
  const double seconds = ctl::series_duration_s(steps) + 0.2;

  lcm::LogFile log(path, "w");
  if (!log.good()) {
    std::fprintf(stderr, "cannot write %s\n", path.c_str());
    return 1;
  }
  bool ok = true;
  std::int64_t eventnum = 0;
  SimulatedStageConfig sc;
  sc.noise_rms_m = 0.5e-9;
  SimulatedStage stage(sc);
  CompensatorConfig cc;
  cc.mode = FeedforwardMode::kOff;
  Compensator comp(cc);
  std::vector<CommandTick> buffer(16'384);  // the bridge's jitter buffer, by tick
  for (auto& c : buffer) c.seq = -1;
  std::array<CommandTick, command_block_t::MAX_TICKS> planned{};
  std::vector<SensorTick> block;
  sensor_block_t sensor{};
  command_block_t command{};
  reserve_storage(sensor);
  reserve_storage(command);
  CommandTick held{};
  const auto ticks = static_cast<std::int64_t>(seconds / cc.dt_s);
  for (std::int64_t seq = kFirstSeq; seq < kFirstSeq + ticks; ++seq) {
    const std::int64_t utime = kUtime0 + (seq - kFirstSeq) * 100;
    const double t = static_cast<double>(seq) * cc.dt_s;
    const CommandTick& slot = buffer[static_cast<std::size_t>(seq) % buffer.size()];
    const bool on_time = slot.seq == seq;
    if (on_time) held = slot;
    const double u = held.u_ff_V;
    const double y = stage.step(u, t, cc.dt_s);
    SensorTick s{utime, seq, u, u, 0.0, on_time ? held.y_ref_m : std::nan(""), y, sensor_block_t::SIMULATED};
    if (!on_time) s.flags |= sensor_block_t::LATE_COMMAND;
    block.push_back(s);
    if (seq == kRequestTick) {
      for (std::size_t i = 0; i < steps.size(); ++i) {
        control_t c{};
        c.utime = utime;
        c.request_id = 7000 + static_cast<std::int64_t>(i);
        c.command = control_t::START_EXPERIMENT;
        c.experiment = steps[i].request.kind;
        c.experiment_amplitude_V = steps[i].request.amplitude_V;
        c.experiment_offset_V = steps[i].request.offset_V;
        c.experiment_frequency_Hz = steps[i].request.frequency_Hz;
        c.experiment_duration_s = steps[i].request.duration_s;
        ok = write_event(log, eventnum, utime, "HX_CONTROL", encoded(c)) && ok;
        comp.start_experiment(ctl::to_spec(steps[i].request));
      }
    }
    if (static_cast<std::int64_t>(block.size()) < kBlockTicks) continue;
    begin_block(sensor, block.front().seq, block.front().utime, cc.dt_s);
    for (const auto& b : block) append_tick(sensor, b);
    sensor.buffer_depth_ticks = 200;
    ok = write_event(log, eventnum, block.back().utime, "HX_SENSOR", encoded(sensor)) && ok;
    for (const auto& b : block) comp.observe({b.seq, b.u_V, b.y_m});
    block.clear();
    while (const std::size_t n = comp.plan(planned)) {
      begin_block(command, planned[0].seq, utime + 20, comp.last_seq());
      for (std::size_t i = 0; i < n; ++i) {
        append_tick(command, planned[i]);
        buffer[static_cast<std::size_t>(planned[i].seq) % buffer.size()] = planned[i];
      }
      ok = write_event(log, eventnum, utime + 20, "HX_COMMAND", encoded(command)) && ok;
    }
  }
  if (!ok) std::fprintf(stderr, "cannot write %s\n", path.c_str());
  return ok ? 0 : 1;
}

}  // namespace
}  // namespace hystloop

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: hystloop_python_banning_log OUT.lcmlog\n");
    return 2;
  }
  return hystloop::record(argv[1]);
}
