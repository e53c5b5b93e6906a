#pragma once
// Test recordings for hystloop-identify: the MEM forward model (common/models/mem.hpp) driven by
// the paper's identification input 250 sin(20 pi t) V at 10 kHz for 2 s, as the bridge would
// publish it on HX_SENSOR, with known faults planted, written with lcm::LogFile.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "hystloop/mem_params_t.hpp"
#include "hystloop/sensor_sample_t.hpp"
#include "models/mem.hpp"

namespace hystloop::testlog {

constexpr std::int64_t kFirstSeq = 1000;                  // a record rarely starts at tick 0
constexpr std::int64_t kFirstUtime = 1'700'000'000'000'000;  // [us]
constexpr std::size_t kTicks = 20'000;                     // 2 s at 10 kHz

// Planted faults, as tick offsets from kFirstSeq.
constexpr std::size_t kSafeBegin = 5000, kSafeCount = 10;    // SAFE_STATE (t = 0.5 s)
constexpr std::size_t kFaultBegin = 7000, kFaultCount = 3;   // SENSOR_FAULT (t = 0.7 s)
constexpr std::size_t kGapBegin = 12'000, kGapCount = 50;    // never recorded (t = 1.2 s)

// Every tick of the record, before faults are planted.
inline std::vector<sensor_sample_t> mem_record(const MemParams& truth, double noise_rms_m = 0.0,
                                               std::uint64_t seed = 7) {
  MemModel model(truth);
  model.reset(0.0);
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, noise_rms_m > 0.0 ? noise_rms_m : 1.0);
  std::vector<sensor_sample_t> out(kTicks);
  for (std::size_t k = 0; k < kTicks; ++k) {
    const double t = static_cast<double>(k) * 1e-4;
    sensor_sample_t& s = out[k];
    s.seq = kFirstSeq + static_cast<std::int64_t>(k);
    s.utime = kFirstUtime + static_cast<std::int64_t>(k) * 100;
    s.u_V = 250.0 * std::sin(20.0 * std::numbers::pi * t);
    s.y_m = model.forward(s.u_V) + (noise_rms_m > 0.0 ? noise(rng) : 0.0);
    s.flags = sensor_sample_t::SIMULATED;
  }
  return out;
}

// The faults: flagged samples carry values that would spoil a fit that kept them (the safe
// voltage and a position far off the loop), and the gap's ticks are removed.
inline std::vector<sensor_sample_t> with_faults(std::vector<sensor_sample_t> record) {
  for (std::size_t k = kSafeBegin; k < kSafeBegin + kSafeCount; ++k) {
    record[k].flags |= sensor_sample_t::SAFE_STATE;
    record[k].u_V = 0.0;
    record[k].y_m = 20e-6;
  }
  for (std::size_t k = kFaultBegin; k < kFaultBegin + kFaultCount; ++k) {
    record[k].flags |= sensor_sample_t::SENSOR_FAULT;
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

// Writes samples [begin, end) on HX_SENSOR, with other traffic in between that the reader must
// ignore or count: another rig's sensor channel, a params message, and (with `corrupt`) one
// mem_params_t and one truncated sample on the sensor channel itself.
inline void write_log(const std::string& path, const std::vector<sensor_sample_t>& samples, std::size_t begin,
                      std::size_t end, bool corrupt = false, const std::string& sensor_channel = "HX_SENSOR") {
  lcm::LogFile log(path, "w");
  ASSERT_TRUE(log.good()) << path;
  std::int64_t eventnum = 0;
  mem_params_t params{};
  params.version = 1;
  params.c1 = 1e-9;
  params.c3 = 1.0;
  for (std::size_t i = begin; i < end; ++i) {
    const sensor_sample_t& s = samples[i];
    write_event(log, eventnum, s.utime, sensor_channel, encoded(s));
    if (i % 1000 == 0) {
      sensor_sample_t other = s;
      other.u_V = -s.u_V;
      other.y_m = 5e-6;
      write_event(log, eventnum, s.utime, "RIG2_SENSOR", encoded(other));
      write_event(log, eventnum, s.utime, "HX_PARAMS", encoded(params));
    }
    if (corrupt && i == begin + 100) {
      write_event(log, eventnum, s.utime, sensor_channel, encoded(params));
      auto cut = encoded(s);
      cut.resize(cut.size() - 3);
      write_event(log, eventnum, s.utime, sensor_channel, cut);
    }
  }
}

inline void write_log(const std::string& path, const std::vector<sensor_sample_t>& samples, bool corrupt = false) {
  write_log(path, samples, 0, samples.size(), corrupt);
}

}  // namespace hystloop::testlog
