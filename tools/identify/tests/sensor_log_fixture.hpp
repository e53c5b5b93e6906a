#pragma once
// Test recordings for hystloop-identify: the MEM forward model (common/models/mem.hpp) driven by
// the paper's identification input 250 sin(20 pi t) V at 10 kHz for 2 s, as the bridge would
// publish it on HX_SENSOR (blocks of up to kBlockTicks consecutive ticks), with known faults
// planted, written with lcm::LogFile.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <numbers>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "hystloop/mem_params_t.hpp"
#include "hystloop/sensor_block_t.hpp"
#include "lcm/blocks.hpp"
#include "models/mem.hpp"

namespace hystloop::testlog {

constexpr std::int64_t kFirstSeq = 1000;                     // a record rarely starts at tick 0
constexpr std::int64_t kFirstUtime = 1'700'000'000'000'000;  // [us]
constexpr std::size_t kTicks = 20'000;                       // 2 s at 10 kHz
constexpr std::size_t kBlockTicks = 10;                      // ticks per HX_SENSOR block

// Planted faults, as tick offsets from kFirstSeq.
constexpr std::size_t kSafeBegin = 5000, kSafeCount = 10;   // SAFE_STATE (t = 0.5 s)
constexpr std::size_t kFaultBegin = 7000, kFaultCount = 3;  // SENSOR_FAULT (t = 0.7 s)
constexpr std::size_t kGapBegin = 12'000, kGapCount = 50;   // never recorded (t = 1.2 s)

// Every tick of the record, before faults are planted.
inline std::vector<SensorTick> mem_record(const MemParams& truth, double noise_rms_m = 0.0, std::uint64_t seed = 7) {
  MemModel model(truth);
  model.reset(0.0);
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, noise_rms_m > 0.0 ? noise_rms_m : 1.0);
  std::vector<SensorTick> out(kTicks);
  for (std::size_t k = 0; k < kTicks; ++k) {
    const double t = static_cast<double>(k) * 1e-4;
    SensorTick& s = out[k];
    s.seq = kFirstSeq + static_cast<std::int64_t>(k);
    s.utime = kFirstUtime + static_cast<std::int64_t>(k) * 100;
    s.u_V = 250.0 * std::sin(20.0 * std::numbers::pi * t);
    s.u_ff_V = s.u_V;
    s.y_ref_m = std::nan("");
    s.y_m = model.forward(s.u_V) + (noise_rms_m > 0.0 ? noise(rng) : 0.0);
    s.flags = sensor_block_t::SIMULATED;
  }
  return out;
}

// The faults: flagged samples carry values that would spoil a fit that kept them (the safe
// voltage and a position far off the loop), and the gap's ticks are removed.
inline std::vector<SensorTick> with_faults(std::vector<SensorTick> record) {
  for (std::size_t k = kSafeBegin; k < kSafeBegin + kSafeCount; ++k) {
    record[k].flags |= sensor_block_t::SAFE_STATE;
    record[k].u_V = 0.0;
    record[k].y_m = 20e-6;
  }
  for (std::size_t k = kFaultBegin; k < kFaultBegin + kFaultCount; ++k) {
    record[k].flags |= sensor_block_t::SENSOR_FAULT;
    record[k].y_m = -20e-6;
  }
  record.erase(record.begin() + kGapBegin, record.begin() + kGapBegin + kGapCount);
  return record;
}

inline void write_event(lcm::LogFile& log, std::int64_t& eventnum, std::int64_t utime, const std::string& channel,
                        std::vector<std::uint8_t> bytes) {
  lcm::LogEvent ev;
  ev.eventnum = eventnum++;
  ev.timestamp = utime;
  ev.channel = channel;
  ev.datalen = static_cast<std::int32_t>(bytes.size());
  ev.data = bytes.data();
  ASSERT_EQ(log.writeEvent(&ev), 0);
}

template <class T>
std::vector<std::uint8_t> encoded(const T& msg) {
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(msg.getEncodedSize()));
  msg.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  return bytes;
}

// The blocks ticks [begin, end) are sent in: runs of consecutive seq, at most kBlockTicks each.
inline std::vector<std::pair<std::size_t, std::size_t>> block_ranges(const std::vector<SensorTick>& ticks,
                                                                     std::size_t begin, std::size_t end) {
  std::vector<std::pair<std::size_t, std::size_t>> ranges;
  for (std::size_t first = begin; first < end;) {
    std::size_t last = first + 1;
    while (last < end && last - first < kBlockTicks && ticks[last].seq == ticks[last - 1].seq + 1) ++last;
    ranges.emplace_back(first, last);
    first = last;
  }
  return ranges;
}

// The block of ticks [first, last): its utime is the first tick's, its ticks dt_s apart.
inline sensor_block_t make_block(const std::vector<SensorTick>& ticks, std::size_t first, std::size_t last,
                                 double dt_s = 1e-4) {
  sensor_block_t b{};
  begin_block(b, ticks[first].seq, ticks[first].utime, dt_s);
  for (std::size_t i = first; i < last; ++i) append_tick(b, ticks[i]);
  b.buffer_depth_ticks = 100;
  return b;
}

// Writes ticks [begin, end) on HX_SENSOR in blocks, with other traffic in between that the
// reader must ignore or count: another rig's sensor channel (a one-tick block with every
// 1000th tick), a params message, and (with `corrupt`) one mem_params_t and one truncated block
// on the sensor channel itself.
inline void write_log(const std::string& path, const std::vector<SensorTick>& ticks, std::size_t begin, std::size_t end,
                      bool corrupt = false, const std::string& sensor_channel = "HX_SENSOR", double dt_s = 1e-4) {
  lcm::LogFile log(path, "w");
  ASSERT_TRUE(log.good()) << path;
  std::int64_t eventnum = 0;
  mem_params_t params{};
  params.version = 1;
  params.c1 = 1e-9;
  params.c3 = 1.0;
  for (const auto& [first, last] : block_ranges(ticks, begin, end)) {
    const sensor_block_t block = make_block(ticks, first, last, dt_s);
    const std::int64_t utime = ticks[last - 1].utime;
    write_event(log, eventnum, utime, sensor_channel, encoded(block));
    for (std::size_t i = first; i < last; ++i) {
      if (i % 1000 == 0) {
        SensorTick other = ticks[i];
        other.u_V = -other.u_V;
        other.y_m = 5e-6;
        const std::vector<SensorTick> one{other};
        write_event(log, eventnum, utime, "RIG2_SENSOR", encoded(make_block(one, 0, 1, dt_s)));
        write_event(log, eventnum, utime, "HX_PARAMS", encoded(params));
      }
      if (corrupt && i == begin + 100) {
        write_event(log, eventnum, utime, sensor_channel, encoded(params));
        auto cut = encoded(block);
        cut.resize(cut.size() - 3);
        write_event(log, eventnum, utime, sensor_channel, cut);
      }
    }
  }
}

inline void write_log(const std::string& path, const std::vector<SensorTick>& ticks, bool corrupt = false) {
  write_log(path, ticks, 0, ticks.size(), corrupt);
}

// Blocks write_log puts on HX_SENSOR for ticks [begin, end).
inline std::size_t blocks_written(const std::vector<SensorTick>& ticks, std::size_t begin, std::size_t end) {
  return block_ranges(ticks, begin, end).size();
}

}  // namespace hystloop::testlog
