// The replay regression's own logic: the tick-by-tick comparison (exact and with tolerance,
// transport losses told apart from divergences), command blocks taken apart into ticks, the
// inputs selection with its warm-up rule, and the deliberate alteration, on logs of blocks
// written here with lcm::LogFile.

#include <gtest/gtest.h>

#include <array>
#include <bit>
#include <cmath>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "command_alteration.hpp"
#include "command_comparison.hpp"
#include "core/errors.hpp"
#include "decode.hpp"
#include "lcm/blocks.hpp"
#include "hystloop/command_block_t.hpp"
#include "hystloop/control_t.hpp"
#include "hystloop/mem_params_t.hpp"
#include "hystloop/sensor_block_t.hpp"
#include "hystloop/service_status_t.hpp"
#include "hystloop/trajectory_t.hpp"
#include "log_reader.hpp"
#include "recorded_commands.hpp"
#include "replay_inputs.hpp"

namespace hystloop::replay {
namespace {

RecordedCommand command(std::int64_t seq) {
  const double s = static_cast<double>(seq);
  return {seq, seq - 2, 0.1 * s + 1.0 / 3.0, 1e-9 * s, 1, 2};
}

CommandLog commands(std::int64_t from, std::int64_t to) {
  CommandLog log;
  for (std::int64_t s = from; s <= to; ++s) log.by_seq[s] = command(s);
  return log;
}

std::set<std::int64_t> samples(std::int64_t from, std::int64_t to) {
  std::set<std::int64_t> out;
  for (std::int64_t s = from; s <= to; ++s) out.insert(s);
  return out;
}

TEST(CompareCommands, IdenticalLogsAreEqual) {
  const CommandLog e = commands(10, 1009);
  const auto r = compare_commands(e, e, nullptr, {});
  EXPECT_EQ(r.compared, 1000u);
  EXPECT_EQ(r.equal, 1000u);
  EXPECT_EQ(r.exit_code(), 0);
  EXPECT_FALSE(r.first_divergence);
  EXPECT_NE(format_report(r, {}).find("verdict: equal"), std::string::npos);
}

TEST(CompareCommands, OneUlpIsADivergenceExactlyButNotWithinATolerance) {
  const CommandLog e = commands(10, 1009);
  CommandLog a = e;
  a.by_seq[500].u_ff_V = std::nextafter(a.by_seq[500].u_ff_V, 1e9);
  a.by_seq[700].u_ff_V += 1.0;
  a.by_seq[800].y_ref_m += 1e-9;
  const auto exact = compare_commands(e, a, nullptr, {});
  ASSERT_TRUE(exact.first_divergence);
  EXPECT_EQ(exact.first_divergence->seq, 500);
  EXPECT_EQ(exact.first_divergence->sample_seq, 498);
  EXPECT_EQ(exact.first_divergence->field, "u_ff_V");
  EXPECT_EQ(exact.first_divergence->expected, e.by_seq.at(500).u_ff_V);
  EXPECT_EQ(exact.differing, 3u);
  EXPECT_EQ(exact.exit_code(), 1);
  const std::string text = format_report(exact, {});
  EXPECT_NE(text.find("FIRST DIVERGENCE at tick 500"), std::string::npos) << text;
  EXPECT_NE(text.find("u_ff_V expected"), std::string::npos) << text;
  EXPECT_NE(text.find("1 of 4 fields differ"), std::string::npos) << text;

  CompareTolerance tol;
  tol.voltage_V = 1e-9;
  auto loose = compare_commands(e, a, nullptr, tol);
  ASSERT_TRUE(loose.first_divergence);
  EXPECT_EQ(loose.first_divergence->seq, 700);
  EXPECT_EQ(loose.first_divergence->field, "u_ff_V");
  tol.voltage_V = 2.0;
  loose = compare_commands(e, a, nullptr, tol);
  ASSERT_TRUE(loose.first_divergence);
  EXPECT_EQ(loose.first_divergence->seq, 800);
  EXPECT_EQ(loose.first_divergence->field, "y_ref_m");  // the voltage tolerance is not the position's
  tol.position_m = 2e-9;
  EXPECT_EQ(compare_commands(e, a, nullptr, tol).exit_code(), 0);
}

TEST(CompareCommands, ModeAndVersionAreAlwaysExact) {
  const CommandLog e = commands(0, 99);
  CommandLog a = e;
  a.by_seq[42].params_version = 2;
  CompareTolerance tol;
  tol.voltage_V = 1e3;
  tol.position_m = 1.0;
  const auto r = compare_commands(e, a, nullptr, tol);
  ASSERT_TRUE(r.first_divergence);
  EXPECT_EQ(r.first_divergence->field, "params_version");
  EXPECT_EQ(r.first_divergence->got, 2.0);
  a = e;
  a.by_seq[43].mode = 0;
  EXPECT_EQ(compare_commands(e, a, nullptr, tol).first_divergence->field, "mode");
}

TEST(CompareCommands, NanReferenceMatchesNan) {
  CommandLog e = commands(0, 9);
  for (auto& [s, c] : e.by_seq) c.y_ref_m = std::numeric_limits<double>::quiet_NaN();
  CommandLog a = e;
  EXPECT_EQ(compare_commands(e, a, nullptr, {}).exit_code(), 0);
  a.by_seq[5].y_ref_m = 0.0;
  EXPECT_EQ(compare_commands(e, a, nullptr, {}).first_divergence->field, "y_ref_m");
}

TEST(CompareCommands, PlayedButUnansweredSamplesAreTransportLosses) {
  const CommandLog e = commands(10, 1009);
  CommandLog a = e;
  a.by_seq.erase(300);  // answers sample 298
  a.by_seq.erase(301);
  const auto played = samples(8, 1007);
  const auto r = compare_commands(e, a, &played, {});
  EXPECT_EQ(r.lost_in_transport, 2u);
  EXPECT_EQ(r.missing_in_actual, 0u);
  EXPECT_EQ(r.first_lost_sample, 298);
  EXPECT_EQ(r.exit_code(), 1);  // the verdict (transport loss) tells it from a divergence
  EXPECT_NE(format_report(r, {}).find("replay transport lost 2 commanded ticks"), std::string::npos)
      << format_report(r, {});

  // A divergence after the loss may be its consequence: still a transport verdict.
  a.by_seq[600].u_ff_V += 1.0;
  auto r2 = compare_commands(e, a, &played, {});
  EXPECT_TRUE(r2.divergence_after_loss);
  EXPECT_EQ(r2.exit_code(), 1);
  // One before it is the control law's.
  a.by_seq[100].u_ff_V += 1.0;
  r2 = compare_commands(e, a, &played, {});
  EXPECT_EQ(r2.first_divergence->seq, 100);
  EXPECT_EQ(r2.exit_code(), 1);
}

TEST(CompareCommands, WithoutThePlayedSetAGapInsideTheAnsweredRangeIsALoss) {
  const CommandLog e = commands(10, 1009);
  CommandLog a = e;
  a.by_seq.erase(500);
  EXPECT_EQ(compare_commands(e, a, nullptr, {}).lost_in_transport, 1u);
  a.by_seq.erase(1009);  // past the last answered sample: not explained
  const auto r = compare_commands(e, a, nullptr, {});
  EXPECT_EQ(r.missing_in_actual, 1u);
  EXPECT_EQ(r.first_missing_seq, 1009);
  EXPECT_EQ(r.exit_code(), 1);
}

TEST(CompareCommands, ReplayOnlyTicksAreCountedNotCompared) {
  const CommandLog e = commands(100, 199);
  const CommandLog a = commands(50, 249);
  const auto r = compare_commands(e, a, nullptr, {});
  EXPECT_EQ(r.compared, 100u);
  EXPECT_EQ(r.missing_in_expected, 100u);
  EXPECT_EQ(r.first_seq, 100);
  EXPECT_EQ(r.last_seq, 199);
  EXPECT_EQ(r.exit_code(), 0);
}

TEST(CompareCommands, NothingComparedFails) {
  const CommandLog e = commands(100, 199);
  const auto played = samples(0, 300);
  const auto r = compare_commands(e, CommandLog{}, &played, {});
  EXPECT_EQ(r.compared, 0u);
  EXPECT_EQ(r.exit_code(), 1);
}

TEST(CompareTolerance, NegativeOrNonFiniteIsRefusedNamingTheField) {
  CompareTolerance t;
  t.voltage_V = -1.0;
  try {
    t.validate();
    FAIL();
  } catch (const ParameterError& e) {
    EXPECT_NE(std::string(e.what()).find("tolerance_V"), std::string::npos);
  }
  t.voltage_V = 0.0;
  t.position_m = std::numeric_limits<double>::infinity();
  EXPECT_THROW(t.validate(), ParameterError);
}

// ---- logs on disk ----

class LogWriter {
 public:
  explicit LogWriter(const std::filesystem::path& path) : file_(path.string(), "w") {}
  template <class T>
  void write(std::int64_t utime, const std::string& channel, const T& msg) {
    std::vector<std::uint8_t> buf(static_cast<std::size_t>(msg.getEncodedSize()));
    msg.encode(buf.data(), 0, static_cast<int>(buf.size()));
    lcm::LogEvent e{0, utime, channel, static_cast<std::int32_t>(buf.size()), buf.data()};
    ASSERT_EQ(file_.writeEvent(&e), 0);
  }

 private:
  lcm::LogFile file_;
};

// Sensor block b: ticks 10b .. 10b + 9, sampled from t = 1 s + 1 ms * b.
sensor_block_t sensor_msg(std::int64_t b) {
  sensor_block_t m{};
  begin_block(m, 10 * b, 1'000'000 + 1000 * b, 1e-4);
  for (std::int64_t t = 10 * b; t < 10 * b + 10; ++t) {
    append_tick(m, SensorTick{0, t, 0.5 * static_cast<double>(t), 0.5 * static_cast<double>(t), 0.0, 1e-9,
                              1e-9 * static_cast<double>(t), 4});
  }
  return m;
}

// Commands for ticks first .. last, planned at sample `sample_seq`.
command_block_t command_msg(std::int64_t first, std::int64_t last, std::int64_t sample_seq) {
  command_block_t m{};
  begin_block(m, first, 1'000'000 + 100 * sample_seq, sample_seq);
  for (std::int64_t t = first; t <= last; ++t) {
    const bool no_reference = t % 7 == 0;
    append_tick(
        m, CommandTick{t, 0.25 * static_cast<double>(t), no_reference ? std::numeric_limits<double>::quiet_NaN() : 1e-9,
                       1, no_reference ? command_block_t::MODE_EXPERIMENT : command_block_t::MODE_MEM});
  }
  return m;
}

control_t control_msg(std::int64_t id) {
  control_t m{};
  m.request_id = id;
  m.command = control_t::SET_MODE;
  m.target = "compensator";
  m.mode = 2;
  return m;
}

mem_params_t params_msg() {
  mem_params_t m{};
  m.version = 2;
  m.c1 = 5e-9;
  m.c2 = 1.7e-12;
  m.c3 = 1.2;
  m.valid = true;
  m.source = "test";
  return m;
}

service_status_t status_msg(const std::string& process, std::int64_t start_utime) {
  service_status_t m{};
  m.process = process;
  m.host = "h";
  m.pid = 42;
  m.state = service_status_t::HEALTHY;
  m.start_utime = start_utime;
  m.loop_p50_us = m.loop_p99_us = m.loop_max_us = std::numeric_limits<double>::quiet_NaN();
  m.latency_p50_us = m.latency_p99_us = m.latency_max_us = std::numeric_limits<double>::quiet_NaN();
  return m;
}

struct TempDir {
  std::filesystem::path path;
  TempDir() {
    path = std::filesystem::temp_directory_path() /
           ("replay_core_test_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::remove_all(path);
    std::filesystem::create_directories(path);
  }
  ~TempDir() { std::filesystem::remove_all(path); }
};

// Sensor blocks 0..19 (ticks 0..199) at 1 ms; the compensator starts at t = 1.0015 s (between
// blocks 1 and 2) and first answers block 2 (sample 29) with ticks 30..79 (its horizon), then
// each block with the 10 ticks 50 ahead of it. It never answers block 5, so its answer to
// block 6 carries ticks 100..119. A control before its start, one after its start but before
// block 2, params mid-run; a status of another process first.
std::filesystem::path write_recorded_log(const std::filesystem::path& dir) {
  auto path = dir / "recorded.lcmlog";
  const ChannelNames c;
  LogWriter w(path);
  w.write(999'000, c.status, status_msg("bridge", 900'000));
  std::int64_t next_unsent = 30;
  for (std::int64_t b = 0; b < 20; ++b) {
    const std::int64_t t = 1'000'000 + 1000 * b;
    if (b == 0) w.write(t - 1, c.control, control_msg(1));
    if (b == 2) w.write(t - 200, c.status, status_msg("compensator", 1'001'500));
    if (b == 2) w.write(t - 100, c.control, control_msg(2));
    if (b == 12) w.write(t - 1, c.params, params_msg());
    w.write(t, c.sensor, sensor_msg(b));
    if (b >= 2 && b != 5) {
      const std::int64_t last = 10 * b + 59;
      w.write(t + 30, c.command, command_msg(next_unsent, last, 10 * b + 9));
      next_unsent = last + 1;
    }
  }
  return path;
}

TEST(RecordedCommands, BlocksAreTakenApartIntoTicksAndARepeatedTickKeepsItsFirstCommand) {
  TempDir tmp;
  const auto path = tmp.path / "commands.lcmlog";
  const ChannelNames c;
  {
    LogWriter w(path);
    w.write(1, c.command, command_msg(100, 109, -1));  // before any sample: not an answer
    auto overlap = command_msg(105, 119, 42);          // 105..109 again
    for (double& u : overlap.u_ff_V) u += 1.0;
    w.write(2, c.command, overlap);
    w.write(3, c.sensor, sensor_msg(1));  // not a command
    auto bad = command_msg(120, 129, 43);
    bad.mode[3] = 9;
    w.write(4, c.command, bad);
  }
  const CommandLog log = read_commands(path, c);
  EXPECT_EQ(log.blocks, 2u);
  EXPECT_EQ(log.undecodable, 1u);
  EXPECT_EQ(log.duplicates, 5u);
  ASSERT_EQ(log.by_seq.size(), 20u);
  EXPECT_EQ(log.by_seq.begin()->first, 100);
  EXPECT_EQ(log.by_seq.rbegin()->first, 119);
  EXPECT_EQ(log.by_seq.at(107).u_ff_V, 0.25 * 107);  // the first block's
  EXPECT_EQ(log.by_seq.at(107).sample_seq, -1);
  EXPECT_EQ(log.by_seq.at(112).u_ff_V, 0.25 * 112 + 1.0);
  EXPECT_EQ(log.by_seq.at(112).sample_seq, 42);
  EXPECT_TRUE(std::isnan(log.by_seq.at(105).y_ref_m));
  EXPECT_EQ(log.by_seq.at(105).mode, command_block_t::MODE_EXPERIMENT);
  EXPECT_EQ(log.answered_samples, (std::set<std::int64_t>{42}));
  EXPECT_EQ(read_sample_seqs(path, c), (std::set<std::int64_t>{10, 11, 12, 13, 14, 15, 16, 17, 18, 19}));
}

TEST(ReplayInputs, StartsAtTheFirstAnsweredBlockAndKeepsInputsFromTheCompensatorsStart) {
  TempDir tmp;
  const auto recorded = write_recorded_log(tmp.path);
  const auto out = tmp.path / "inputs.lcmlog";
  const ChannelNames c;
  const ReplayInputSelection s = write_replay_inputs(recorded, out, c, {});
  EXPECT_EQ(s.first_log_sample, 0);
  EXPECT_EQ(s.first_answered_sample, 29);
  EXPECT_EQ(s.compensator_start_utime, 1'001'500);
  EXPECT_FALSE(s.log_starts_after_compensator);
  EXPECT_EQ(s.blocks_before_start, 2u);
  EXPECT_EQ(s.blocks_written, 18u);
  EXPECT_EQ(s.ticks_written, 180u);
  EXPECT_EQ(s.blocks_unanswered, 1u);
  EXPECT_EQ(s.other_inputs_written, 2u);  // control 2 (after the start), params
  EXPECT_EQ(s.other_inputs_skipped, 1u);  // control 1
  EXPECT_NE(describe(s).find("the replay starts with the block of sample 29"), std::string::npos) << describe(s);
  EXPECT_NE(describe(s).find("18 sensor blocks (180 ticks)"), std::string::npos) << describe(s);

  std::vector<std::string> channels;
  std::int64_t first_seq = -1;
  sensor_block_t m;
  report::for_each_event({out}, [&](const lcm::LogEvent& e) {
    channels.push_back(e.channel);
    if (e.channel == c.sensor && first_seq < 0) {
      m.decode(e.data, 0, e.datalen);
      first_seq = m.seq;
    }
  });
  EXPECT_EQ(first_seq, 20);
  EXPECT_EQ(channels.front(), c.control);  // control 2 precedes block 2, original order kept
  for (const auto& ch : channels) {
    EXPECT_TRUE(ch == c.sensor || ch == c.control || ch == c.params) << ch;
  }
  EXPECT_EQ(read_sample_seqs(out, c).size(), 180u);
}

TEST(ReplayInputs, OnlyAnsweredDropsTheBlockTheOriginalDidNotAnswer) {
  TempDir tmp;
  const auto recorded = write_recorded_log(tmp.path);
  ReplayInputOptions opt;
  opt.only_answered = true;
  const auto s = write_replay_inputs(recorded, tmp.path / "inputs.lcmlog", ChannelNames{}, opt);
  EXPECT_EQ(s.blocks_written, 17u);
  EXPECT_EQ(s.blocks_unanswered_dropped, 1u);
  const auto played = read_sample_seqs(tmp.path / "inputs.lcmlog", ChannelNames{});
  EXPECT_EQ(played.count(50) + played.count(59), 0u);
  EXPECT_EQ(played.count(60), 1u);
}

// The original's commands against themselves, with the played sample ticks: every tick is
// reproduced, whatever block it came in; without the block answering 6 (ticks 100..119) the
// loss is the transport's, since sample 69 was played.
TEST(ReplayInputs, TheRecordedCommandsCompareTickByTick) {
  TempDir tmp;
  const auto recorded = write_recorded_log(tmp.path);
  const ChannelNames c;
  write_replay_inputs(recorded, tmp.path / "inputs.lcmlog", c, {});
  const CommandLog e = read_commands(recorded, c);
  const auto played = read_sample_seqs(tmp.path / "inputs.lcmlog", c);
  EXPECT_EQ(e.by_seq.begin()->first, 30);
  EXPECT_EQ(e.by_seq.rbegin()->first, 249);
  EXPECT_EQ(e.by_seq.size(), 220u);
  EXPECT_EQ(compare_commands(e, e, &played, {}).exit_code(), 0);
  CommandLog a = e;
  for (std::int64_t t = 100; t <= 119; ++t) a.by_seq.erase(t);
  const auto r = compare_commands(e, a, &played, {});
  EXPECT_EQ(r.lost_in_transport, 20u);
  EXPECT_EQ(r.first_lost_sample, 69);
  EXPECT_EQ(r.exit_code(), 1);
}

TEST(ReplayInputs, ALogWithoutCommandsOrFileIsRefused) {
  TempDir tmp;
  const auto path = tmp.path / "samples_only.lcmlog";
  {
    LogWriter w(path);
    w.write(1, ChannelNames{}.sensor, sensor_msg(1));
    w.write(2, ChannelNames{}.command, command_msg(20, 29, -1));  // answers no sample
  }
  EXPECT_THROW(write_replay_inputs(path, tmp.path / "o.lcmlog", ChannelNames{}, {}), std::runtime_error);
  EXPECT_THROW(write_replay_inputs(tmp.path / "absent.lcmlog", tmp.path / "o.lcmlog", ChannelNames{}, {}),
               std::runtime_error);
}

TEST(CommandAlteration, ChangesExactlyOneTickAndTheComparisonNamesIt) {
  TempDir tmp;
  const auto recorded = write_recorded_log(tmp.path);
  const auto altered = tmp.path / "altered.lcmlog";
  const ChannelNames c;
  const auto r = write_altered_log(recorded, altered, c, {40, std::nullopt, std::nullopt});
  EXPECT_EQ(r.seq, 40);
  EXPECT_EQ(r.old_u_ff_V, 0.25 * 40);
  EXPECT_EQ(std::bit_cast<std::uint64_t>(r.old_u_ff_V) ^ std::bit_cast<std::uint64_t>(r.new_u_ff_V), 1u);
  const CommandLog e = read_commands(recorded, c);
  const CommandLog a = read_commands(altered, c);
  EXPECT_EQ(a.by_seq.size(), e.by_seq.size());
  EXPECT_EQ(a.blocks, e.blocks);
  const auto report = compare_commands(a, e, nullptr, {});
  EXPECT_EQ(report.differing, 1u);
  EXPECT_EQ(report.first_divergence->seq, 40);
  EXPECT_EQ(report.first_divergence->field, "u_ff_V");
  EXPECT_EQ(report.first_divergence->fields_differing, 1);

  const auto r2 = write_altered_log(recorded, altered, c, {141, std::nullopt, 0.5});
  EXPECT_EQ(r2.new_u_ff_V, r2.old_u_ff_V + 0.5);
  EXPECT_EQ(compare_commands(e, read_commands(altered, c), nullptr, {}).first_divergence->seq, 141);
  EXPECT_THROW(write_altered_log(recorded, altered, c, {5, std::nullopt, std::nullopt}),
               std::runtime_error);  // no tick 5
  // The first block carries ticks 30..79: the 10th tick commanded is 39, the 60th is 89.
  EXPECT_EQ(write_altered_log(recorded, altered, c, {0, 10, std::nullopt}).seq, 39);
  EXPECT_EQ(write_altered_log(recorded, altered, c, {0, 60, std::nullopt}).seq, 89);
  EXPECT_THROW(write_altered_log(recorded, altered, c, {0, 1000, std::nullopt}), std::runtime_error);
}

// A log of two axes: the altered block keeps both, y's commands untouched.
TEST(CommandAlteration, KeepsEveryAxisOfABlock) {
  TempDir tmp;
  const auto recorded = tmp.path / "xy.lcmlog";
  const ChannelNames c;
  command_block_t xy{};
  {
    LogWriter w(recorded);
    begin_block(xy, 30, 1'000'000, 29, 2);
    for (std::int64_t t = 30; t < 40; ++t) {
      const std::array<CommandTick, 2> both{CommandTick{t, 0.25 * static_cast<double>(t), 1e-9, 1, 2},
                                            CommandTick{t, -0.5 * static_cast<double>(t), 2e-9, 1, 2}};
      ASSERT_TRUE(append_tick(xy, both));
    }
    w.write(1'000'100, c.command, xy);
  }
  const auto altered = tmp.path / "altered.lcmlog";
  const auto r = write_altered_log(recorded, altered, c, {35, std::nullopt, 1.0});
  EXPECT_EQ(r.seq, 35);
  lcm::LogFile log(altered.string(), "r");
  const lcm::LogEvent* e = log.readNextEvent();
  ASSERT_NE(e, nullptr);
  command_block_t got{};
  ASSERT_TRUE(report::decode_checked(*e, got));
  ASSERT_EQ(got.n_axes, 2);
  ASSERT_EQ(got.n_ticks, 10);
  for (std::size_t i = 0; i < 10; ++i) {
    const double t = 30.0 + static_cast<double>(i);
    EXPECT_EQ(command_tick(got, i, 0).u_ff_V, 0.25 * t + (i == 5 ? 1.0 : 0.0)) << i;
    EXPECT_EQ(command_tick(got, i, 1).u_ff_V, -0.5 * t) << i;
    EXPECT_EQ(command_tick(got, i, 1).y_ref_m, 2e-9) << i;
  }
}

}  // namespace
}  // namespace hystloop::replay
