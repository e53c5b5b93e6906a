// The replay regression's own logic: the tick-by-tick comparison (exact and with tolerance,
// transport losses told apart from divergences), the inputs selection with its warm-up
// rule, and the deliberate alteration, on logs written here with lcm::LogFile.

#include <gtest/gtest.h>

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
#include "hystloop/actuator_command_t.hpp"
#include "hystloop/control_t.hpp"
#include "hystloop/mem_params_t.hpp"
#include "hystloop/sensor_sample_t.hpp"
#include "hystloop/service_status_t.hpp"
#include "hystloop/trajectory_t.hpp"
#include "log_reader.hpp"
#include "recorded_commands.hpp"
#include "replay_inputs.hpp"

namespace hystloop::replay {
namespace {

RecordedCommand command(std::int64_t seq) {
  const double s = static_cast<double>(seq);
  return {seq, seq - 2, 0.1 * s + 1.0 / 3.0, 0.1 * s, 1.0 / 3.0, 1e-9 * s, 1, 2};
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
  a.by_seq[500].u_V = std::nextafter(a.by_seq[500].u_V, 1e9);
  a.by_seq[700].u_fb_V += 1.0;
  const auto exact = compare_commands(e, a, nullptr, {});
  ASSERT_TRUE(exact.first_divergence);
  EXPECT_EQ(exact.first_divergence->seq, 500);
  EXPECT_EQ(exact.first_divergence->sample_seq, 498);
  EXPECT_EQ(exact.first_divergence->field, "u_V");
  EXPECT_EQ(exact.first_divergence->expected, e.by_seq.at(500).u_V);
  EXPECT_EQ(exact.differing, 2u);
  EXPECT_EQ(exact.exit_code(), 1);
  const std::string text = format_report(exact, {});
  EXPECT_NE(text.find("FIRST DIVERGENCE at tick 500"), std::string::npos) << text;
  EXPECT_NE(text.find("u_V expected"), std::string::npos) << text;

  CompareTolerance tol;
  tol.voltage_V = 1e-9;
  const auto loose = compare_commands(e, a, nullptr, tol);
  ASSERT_TRUE(loose.first_divergence);
  EXPECT_EQ(loose.first_divergence->seq, 700);
  EXPECT_EQ(loose.first_divergence->field, "u_fb_V");
  tol.voltage_V = 2.0;
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
  EXPECT_EQ(r.exit_code(), 3);
  EXPECT_NE(format_report(r, {}).find("replay transport lost 2 samples"), std::string::npos);

  // A divergence after the loss may be its consequence: still a transport verdict.
  a.by_seq[600].u_V += 1.0;
  auto r2 = compare_commands(e, a, &played, {});
  EXPECT_TRUE(r2.divergence_after_loss);
  EXPECT_EQ(r2.exit_code(), 3);
  // One before it is the control law's.
  a.by_seq[100].u_V += 1.0;
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

sensor_sample_t sample_msg(std::int64_t seq) {
  sensor_sample_t m{};
  m.seq = seq;
  m.utime = 1'000'000 + 100 * seq;
  m.u_V = 0.5 * static_cast<double>(seq);
  m.y_m = 1e-9 * static_cast<double>(seq);
  m.flags = 4;
  return m;
}

actuator_command_t command_msg(std::int64_t sample_seq) {
  actuator_command_t m{};
  m.seq = sample_seq + 2;
  m.sample_seq = sample_seq;
  m.utime = 1'000'000 + 100 * sample_seq;
  m.u_V = 0.25 * static_cast<double>(sample_seq);
  m.u_ff_V = m.u_V;
  m.y_ref_m = 1e-9;
  m.params_version = 1;
  m.mode = 2;
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

// Samples 0..99 at 100 us; the compensator starts at t = 1.0015 s (between samples 14 and 15)
// and first answers sample 20; it never answers sample 50. A control before its start, one
// after its start but before sample 20, params mid-run; a status of another process first.
std::filesystem::path write_recorded_log(const std::filesystem::path& dir) {
  const auto path = dir / "recorded.lcmlog";
  const ChannelNames c;
  LogWriter w(path);
  w.write(999'000, c.status, status_msg("bridge", 900'000));
  for (std::int64_t s = 0; s < 100; ++s) {
    const std::int64_t t = 1'000'000 + 100 * s;
    if (s == 5) w.write(t - 1, c.control, control_msg(1));
    if (s == 16) w.write(t - 1, c.status, status_msg("compensator", 1'001'500));
    if (s == 17) w.write(t - 1, c.control, control_msg(2));
    if (s == 60) w.write(t - 1, c.params, params_msg());
    w.write(t, c.sensor, sample_msg(s));
    if (s >= 20 && s != 50) w.write(t + 30, c.command, command_msg(s));
  }
  return path;
}

TEST(ReplayInputs, StartsAtTheFirstAnsweredSampleAndKeepsInputsFromTheCompensatorsStart) {
  TempDir tmp;
  const auto recorded = write_recorded_log(tmp.path);
  const auto out = tmp.path / "inputs.lcmlog";
  const ChannelNames c;
  const ReplayInputSelection s = write_replay_inputs(recorded, out, c, {});
  EXPECT_EQ(s.first_log_sample, 0);
  EXPECT_EQ(s.first_answered_sample, 20);
  EXPECT_EQ(s.compensator_start_utime, 1'001'500);
  EXPECT_FALSE(s.log_starts_after_compensator);
  EXPECT_EQ(s.samples_before_start, 20u);
  EXPECT_EQ(s.samples_written, 80u);
  EXPECT_EQ(s.samples_unanswered, 1u);
  EXPECT_EQ(s.other_inputs_written, 2u);  // control 2 (after the start), params
  EXPECT_EQ(s.other_inputs_skipped, 1u);  // control 1
  EXPECT_NE(describe(s).find("the replay starts at sample 20"), std::string::npos) << describe(s);

  std::vector<std::string> channels;
  std::int64_t first_seq = -1;
  sensor_sample_t m;
  report::for_each_event({out}, [&](const lcm::LogEvent& e) {
    channels.push_back(e.channel);
    if (e.channel == c.sensor && first_seq < 0) {
      m.decode(e.data, 0, e.datalen);
      first_seq = m.seq;
    }
  });
  EXPECT_EQ(first_seq, 20);
  EXPECT_EQ(channels.front(), c.control);  // control 2 precedes sample 20, original order kept
  for (const auto& ch : channels) {
    EXPECT_TRUE(ch == c.sensor || ch == c.control || ch == c.params) << ch;
  }
  EXPECT_EQ(read_sample_seqs(out, c).size(), 80u);
}

TEST(ReplayInputs, OnlyAnsweredDropsTheGapTheOriginalSaw) {
  TempDir tmp;
  const auto recorded = write_recorded_log(tmp.path);
  ReplayInputOptions opt;
  opt.only_answered = true;
  const auto s = write_replay_inputs(recorded, tmp.path / "inputs.lcmlog", ChannelNames{}, opt);
  EXPECT_EQ(s.samples_written, 79u);
  EXPECT_EQ(s.samples_unanswered_dropped, 1u);
  EXPECT_EQ(read_sample_seqs(tmp.path / "inputs.lcmlog", ChannelNames{}).count(50), 0u);
}

TEST(ReplayInputs, ALogWithoutCommandsOrFileIsRefused) {
  TempDir tmp;
  const auto path = tmp.path / "samples_only.lcmlog";
  {
    LogWriter w(path);
    w.write(1, ChannelNames{}.sensor, sample_msg(1));
  }
  EXPECT_THROW(write_replay_inputs(path, tmp.path / "o.lcmlog", ChannelNames{}, {}), std::runtime_error);
  EXPECT_THROW(write_replay_inputs(tmp.path / "absent.lcmlog", tmp.path / "o.lcmlog", ChannelNames{}, {}),
               std::runtime_error);
}

TEST(CommandAlteration, ChangesExactlyOneCommandAndTheComparisonNamesIt) {
  TempDir tmp;
  const auto recorded = write_recorded_log(tmp.path);
  const auto altered = tmp.path / "altered.lcmlog";
  const ChannelNames c;
  const auto r = write_altered_log(recorded, altered, c, {40, std::nullopt, std::nullopt});
  EXPECT_EQ(r.seq, 40);
  EXPECT_EQ(std::bit_cast<std::uint64_t>(r.old_u_V) ^ std::bit_cast<std::uint64_t>(r.new_u_V), 1u);
  const CommandLog e = read_commands(recorded, c);
  const CommandLog a = read_commands(altered, c);
  EXPECT_EQ(a.by_seq.size(), e.by_seq.size());
  const auto report = compare_commands(a, e, nullptr, {});
  EXPECT_EQ(report.differing, 1u);
  EXPECT_EQ(report.first_divergence->seq, 40);
  EXPECT_EQ(report.first_divergence->field, "u_V");

  const auto r2 = write_altered_log(recorded, altered, c, {41, std::nullopt, 0.5});
  EXPECT_EQ(r2.new_u_V, r2.old_u_V + 0.5);
  EXPECT_THROW(write_altered_log(recorded, altered, c, {5, std::nullopt, std::nullopt}), std::runtime_error);  // no tick 5
  // The 10th command answers sample 29: tick 31.
  EXPECT_EQ(write_altered_log(recorded, altered, c, {0, 10, std::nullopt}).seq, 31);
  EXPECT_THROW(write_altered_log(recorded, altered, c, {0, 1000, std::nullopt}), std::runtime_error);
}

}  // namespace
}  // namespace hystloop::replay
