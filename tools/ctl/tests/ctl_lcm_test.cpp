// hystloop-ctl against real udpm LCM (ttl=0) inside tools/netns-run: this test subscribes,
// runs the tool as a child process, keeps dispatching (and, where needed, plays the rig by
// publishing statuses, samples and commands) until the child exits, then checks what
// arrived and what the tool printed. Argument errors and --help need no LCM and always run.
#include <gtest/gtest.h>

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <memory>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "hystloop/command_block_t.hpp"
#include "hystloop/sensor_block_t.hpp"
#include "lcm/blocks.hpp"
#include "lcm/channels.hpp"
#include "lcm/connection.hpp"
#include "lcm/publisher.hpp"
#include "lcm/subscription.hpp"

extern char** environ;

namespace fs = std::filesystem;
using namespace hystloop;

namespace {

const std::string kUrl = "udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304";

struct Result {
  int exit_code = -1;
  std::string out, err;
};

std::string slurp(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::int64_t now_us() {
  return std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}

// Runs hystloop-ctl with args; while it runs, calls tick() every ~2 ms (after dispatching
// whatever LCM has for `lcm`, if given).
Result run_ctl(const std::vector<std::string>& args, lcm::LCM* lcm = nullptr, const std::function<void()>& tick = {}) {
  const fs::path dir = fs::temp_directory_path();
  const fs::path out = dir / ("ctl_out_" + std::to_string(::getpid()));
  const fs::path err = dir / ("ctl_err_" + std::to_string(::getpid()));
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 1, out.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_addopen(&actions, 2, err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  std::vector<std::string> all{HYSTLOOP_CTL_EXE};
  all.insert(all.end(), args.begin(), args.end());
  std::vector<char*> argv;
  argv.reserve(all.size() + 1);
  for (auto& a : all) argv.push_back(a.data());
  argv.push_back(nullptr);
  pid_t pid = 0;
  Result r;
  if (posix_spawn(&pid, HYSTLOOP_CTL_EXE, &actions, nullptr, argv.data(), environ) != 0) return r;
  posix_spawn_file_actions_destroy(&actions);
  int status = 0;
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while (true) {
    const pid_t done = ::waitpid(pid, &status, WNOHANG);
    if (done == pid) break;
    if (std::chrono::steady_clock::now() > give_up) {
      ::kill(pid, SIGKILL);
      ::waitpid(pid, &status, 0);
      break;
    }
    if (lcm != nullptr) {
      handle_pending(*lcm, std::chrono::microseconds(2000));
    } else {
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
    if (tick) tick();
  }
  if (lcm != nullptr) handle_pending(*lcm, std::chrono::microseconds(20'000));  // stragglers
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = slurp(out);
  r.err = slurp(err);
  fs::remove(out);
  fs::remove(err);
  return r;
}

bool in_netns() { return std::getenv("HYSTLOOP_NETNS") != nullptr; }

class CtlLcmTest : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!in_netns()) GTEST_SKIP() << "needs udpm LCM: run inside tools/netns-run";
    lcm_ = open_lcm(kUrl);
  }
  std::unique_ptr<lcm::LCM> lcm_;
  ChannelNames ch_;
};

std::vector<std::string> with_url(std::vector<std::string> args) {
  args.insert(args.begin(), {"--lcm-url", kUrl});
  return args;
}

service_status_t status_of(const std::string& process, std::int8_t state, std::int64_t late = 0) {
  service_status_t s{};
  s.utime = now_us();
  s.process = process;
  s.host = "test";
  s.pid = static_cast<std::int32_t>(::getpid());
  s.state = state;
  s.start_utime = s.utime - 1'000'000;
  s.loop_p50_us = s.loop_p99_us = s.loop_max_us = std::nan("");
  s.latency_p50_us = 40.0;
  s.latency_p99_us = 95.0;
  s.latency_max_us = 300.0;
  s.late = late;
  return s;
}

}  // namespace

TEST_F(CtlLcmTest, EveryControlKindArrivesThreeTimesWithOneRequestId) {
  std::vector<control_t> got;
  Subscription<control_t> sub(*lcm_, ch_.control, [&](const control_t& c, std::int64_t) { got.push_back(c); });
  struct Case {
    std::vector<std::string> args;
    std::int8_t command;
    std::string target;
    std::function<void(const control_t&)> check;
  };
  const std::vector<Case> cases{
      {{"arm"}, control_t::ARM, "", {}},
      {{"disarm", "--target", "bridge"}, control_t::DISARM, "bridge", {}},
      {{"shutdown", "compensator"}, control_t::SHUTDOWN, "compensator", {}},
      {{"shutdown"}, control_t::SHUTDOWN, "", {}},
      {{"reset-counters", "bridge"}, control_t::RESET_COUNTERS, "bridge", {}},
      {{"stop-experiment"}, control_t::STOP_EXPERIMENT, "", {}},
      {{"mode", "mem"},
       control_t::SET_MODE,
       "",
       [](const control_t& c) { EXPECT_EQ(c.mode, command_block_t::MODE_MEM); }},
      {{"mode", "pi", "--target", "compensator"},
       control_t::SET_MODE,
       "compensator",
       [](const control_t& c) { EXPECT_EQ(c.mode, command_block_t::MODE_PI); }},
      {{"gains", "--kp", "0.5", "--ki", "20", "--kd", "1e-5"},
       control_t::SET_GAINS,
       "bridge",  // the servo's home
       [](const control_t& c) {
         EXPECT_EQ(c.kp, 0.5);
         EXPECT_EQ(c.ki, 20.0);
         EXPECT_EQ(c.kd, 1e-5);
       }},
      {{"gains", "--kp", "0.1", "--target", "bridge2"},
       control_t::SET_GAINS,
       "bridge2",
       [](const control_t& c) {
         EXPECT_EQ(c.kp, 0.1);
         EXPECT_TRUE(std::isnan(c.ki));        // not given: the bridge keeps its own
         EXPECT_TRUE(std::isnan(c.notch_hz));  // ... and its notch
       }},
      {{"gains", "--kp", "0.2", "--notch-hz", "1720", "--notch-q", "3.5"},
       control_t::SET_GAINS,
       "bridge",
       [](const control_t& c) {
         EXPECT_EQ(c.notch_hz, 1720.0);
         EXPECT_EQ(c.notch_q, 3.5);
       }},
      {{"learn", "on"},
       control_t::SET_LEARNING,
       "compensator",  // the one that learns
       [](const control_t& c) { EXPECT_EQ(c.learning, control_t::LEARNING_ON); }},
      {{"learn", "off", "--target", "compensator2"},
       control_t::SET_LEARNING,
       "compensator2",
       [](const control_t& c) { EXPECT_EQ(c.learning, control_t::LEARNING_OFF); }},
      {{"learn", "reset"},
       control_t::SET_LEARNING,
       "compensator",
       [](const control_t& c) { EXPECT_EQ(c.learning, control_t::LEARNING_RESET); }},
      {{"experiment", "--amplitude", "50", "--frequency", "2", "--duration", "10", "--offset", "-5", "--kind",
        "settle"},
       control_t::START_EXPERIMENT,
       "",
       [](const control_t& c) {
         EXPECT_EQ(c.experiment, "settle");
         EXPECT_EQ(c.experiment_amplitude_V, 50.0);
         EXPECT_EQ(c.experiment_frequency_Hz, 2.0);
         EXPECT_EQ(c.experiment_duration_s, 10.0);
         EXPECT_EQ(c.experiment_offset_V, -5.0);
       }},
  };
  std::vector<std::int64_t> ids;
  for (const auto& c : cases) {
    got.clear();
    std::vector<std::string> args = c.args;
    args.emplace_back("--no-wait");  // nobody answers here: ControlsWaitForTheAnswer covers that
    const Result r = run_ctl(with_url(args), lcm_.get());
    ASSERT_EQ(r.exit_code, 0) << c.args[0] << ": " << r.err;
    ASSERT_EQ(got.size(), 3u) << c.args[0];
    for (const auto& msg : got) {
      EXPECT_EQ(msg.command, c.command) << c.args[0];
      EXPECT_EQ(msg.target, c.target) << c.args[0];
      EXPECT_EQ(msg.request_id, got[0].request_id) << c.args[0];
      EXPECT_GT(msg.request_id, 0);
      EXPECT_NEAR(static_cast<double>(msg.utime), static_cast<double>(now_us()), 10e6);
      if (c.check) c.check(msg);
    }
    EXPECT_EQ(std::count(ids.begin(), ids.end(), got[0].request_id), 0) << "request ids must differ";
    ids.push_back(got[0].request_id);
  }
}

// Every request that changes state waits for the process it is for to answer on HX_STATUS
// (control_acted_request / control_refused_request carry the request id), and says who did not.
TEST_F(CtlLcmTest, ControlsWaitForTheAnswerOfTheProcessTheyAreFor) {
  Publisher<service_status_t> status(*lcm_, ch_.status);
  struct Player {
    std::string process;
    enum class Answer { kAct, kActNoChange, kRefuse, kSilent } answer = Answer::kAct;
  };
  std::vector<Player> players;
  std::int64_t last_id = 0;
  std::vector<std::int64_t> gains_counters{100'000, 600'000'000, 0, 0, 0};  // kp 0.1, ki 600 1/s
  Subscription<control_t> sub(*lcm_, ch_.control, [&](const control_t& c, std::int64_t) { last_id = c.request_id; });
  int ticks = 0;
  auto play = [&] {
    if (++ticks % 10 != 0) return;  // every ~20 ms
    for (const Player& p : players) {
      if (p.answer == Player::Answer::kSilent) continue;
      service_status_t s = status_of(p.process, service_status_t::HEALTHY);
      const bool refuse = p.answer == Player::Answer::kRefuse;
      s.counter_names = {"control_acted_request", "control_refused_request", "armed",
                         "servo_kp_ppm",          "servo_ki_ppm_per_s",      "servo_kd_ps",
                         "servo_notch_mHz",       "servo_notch_q_ppm"};
      s.counter_values = {refuse ? 0 : last_id, refuse ? last_id : 0, p.answer == Player::Answer::kAct ? 1 : 0};
      s.counter_values.insert(s.counter_values.end(), gains_counters.begin(), gains_counters.end());
      s.n_counters = static_cast<std::int32_t>(s.counter_names.size());
      if (refuse) s.detail = "request " + std::to_string(last_id) + " refused: not today";
      status.publish(s);
    }
  };
  auto run = [&](std::vector<std::string> args, std::vector<Player> who) {
    players = std::move(who);
    last_id = 0;
    return run_ctl(with_url(std::move(args)), lcm_.get(), play);
  };
  using A = Player::Answer;

  Result r = run({"arm"}, {{"bridge", A::kAct}, {"compensator", A::kSilent}});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("'bridge' confirmed"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("ARM confirmed in "), std::string::npos) << r.out;

  // Taken, but the state it asks for does not show: not confirmed.
  r = run({"arm", "--timeout", "0.5"}, {{"bridge", A::kActNoChange}});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("'bridge' took it, but its report does not show the change yet"), std::string::npos) << r.err;

  r = run({"mode", "mem"}, {{"compensator", A::kRefuse}});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("'compensator' refused it: not today"), std::string::npos) << r.err;

  r = run({"arm", "--timeout", "0.5"}, {{"compensator", A::kAct}});  // the bridge is missing
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("'bridge' sent no status report"), std::string::npos) << r.err;

  r = run({"disarm", "--timeout", "0.5"}, {});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("no rig is running"), std::string::npos) << r.err;

  // To every process: each one heard must answer.
  r = run({"reset-counters"}, {{"bridge", A::kAct}, {"logger", A::kAct}});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("'bridge' confirmed"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("'logger' confirmed"), std::string::npos) << r.out;
  r = run({"reset-counters", "--timeout", "1.5"}, {{"bridge", A::kAct}, {"logger", A::kRefuse}});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("'logger' refused it"), std::string::npos) << r.err;

  // gains without a gain: the gains in force; with one, the others stay and the result is printed.
  r = run({"gains"}, {{"bridge", A::kAct}});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("servo gains in force: kp 0.1, ki 600 1/s, kd 0 s, no notch"), std::string::npos) << r.out;
  gains_counters = {200'000, 600'000'000, 0, 1'720'000, 3'000'000};
  r = run({"gains", "--kp", "0.2"}, {{"bridge", A::kAct}});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("kp 0.2, ki 600 1/s, kd 0 s, notch at 1720 Hz (Q 3)"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("margins not checked"), std::string::npos) << r.out;

  // With the stage model the compensator inverts (here a two-mode stage with 1.5 ticks of delay):
  // the margins of the gains as they will be, before anything is sent. Banning's servo there is
  // unstable: refused, nothing sent, unless forced; a notch on the first mode is stable but short
  // of phase: sent, with a warning.
  const std::filesystem::path stage_yaml =
      std::filesystem::temp_directory_path() / ("ctl_gains_stage_" + std::to_string(::getpid()) + ".yaml");
  std::ofstream(stage_yaml) << "stage:\n  kind: linear\n  modes:\n"
                               "    - {frequency_hz: 780, damping_ratio: 0.03, weight: 0.92}\n"
                               "    - {frequency_hz: 2400, damping_ratio: 0.02, weight: 0.08}\n"
                               "  delay_s: 1.5e-4\n";
  const std::vector<std::string> banning_servo{"gains",
                                               "--kp",
                                               "0.05",
                                               "--ki",
                                               "2000",
                                               "--notch-hz",
                                               "1720",
                                               "--notch-q",
                                               "0.7",
                                               "--stage-config",
                                               stage_yaml.string()};
  r = run(banning_servo, {{"bridge", A::kAct}});
  EXPECT_EQ(r.exit_code, 2) << r.out << r.err;
  EXPECT_NE(r.out.find("servo x on the stage of " + stage_yaml.string() + ": UNSTABLE"), std::string::npos) << r.out;
  EXPECT_NE(r.err.find("not sent: the loop would be unstable"), std::string::npos) << r.err;
  EXPECT_EQ(last_id, 0) << "a SET_GAINS went out";
  std::vector<std::string> forced = banning_servo;
  forced.push_back("--force");
  r = run(forced, {{"bridge", A::kAct}});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(last_id, 0);
  r = run({"gains", "--notch-hz", "780", "--notch-q", "0.5", "--kp", "0.05", "--ki", "2000", "--stage-config",
           stage_yaml.string()},
          {{"bridge", A::kAct}});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(last_id, 0);
  EXPECT_NE(r.err.find("WARNING: phase margin"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("WARNING: gain margin"), std::string::npos) << r.err;
  std::filesystem::remove(stage_yaml);

  // --no-wait: today's fire and forget.
  r = run({"arm", "--no-wait"}, {});
  EXPECT_EQ(r.exit_code, 0) << r.err;
}

TEST_F(CtlLcmTest, TrajectoriesArriveAsSent) {
  std::vector<trajectory_t> got;
  Subscription<trajectory_t> sub(*lcm_, ch_.trajectory, [&](const trajectory_t& t, std::int64_t) { got.push_back(t); });

  Result r = run_ctl(with_url({"trajectory", "--mem-paper", "--blend", "0.5", "--no-wait"}), lcm_.get());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  ASSERT_EQ(got.size(), 3u);
  EXPECT_EQ(got[0].shape, trajectory_t::COSINE);
  EXPECT_DOUBLE_EQ(got[0].amplitude_m, -1.6e-6);
  EXPECT_DOUBLE_EQ(got[0].frequency_Hz, 1.0);
  EXPECT_DOUBLE_EQ(got[0].blend_s, 0.5);
  EXPECT_EQ(got[2].version, got[0].version);
  const std::int64_t first_version = got[0].version;

  got.clear();
  r = run_ctl(with_url({"trajectory", "--shape", "triangle", "--amplitude", "2e-6", "--frequency", "5", "--offset",
                        "1e-7", "--blend", "0", "--no-wait"}),
              lcm_.get());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  ASSERT_EQ(got.size(), 3u);
  EXPECT_EQ(got[0].shape, trajectory_t::TRIANGLE);
  EXPECT_DOUBLE_EQ(got[0].amplitude_m, 2e-6);
  EXPECT_DOUBLE_EQ(got[0].frequency_Hz, 5.0);
  EXPECT_DOUBLE_EQ(got[0].offset_m, 1e-7);
  EXPECT_EQ(got[0].corner_s, 0.0);  // the compensator chooses
  EXPECT_EQ(got[0].if_infeasible, trajectory_t::REFUSE);
  EXPECT_GT(got[0].version, first_version);  // a new trajectory supersedes the last
  EXPECT_NE(r.out.find("corner: the shortest feasible"), std::string::npos) << r.out;

  got.clear();
  r = run_ctl(with_url({"trajectory", "--shape", "triangle", "--amplitude", "1e-6", "--frequency", "10", "--corner",
                        "0.004", "--shape-to-feasible", "--no-wait"}),
              lcm_.get());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  ASSERT_EQ(got.size(), 3u);
  EXPECT_EQ(got[0].corner_s, 0.004);
  EXPECT_EQ(got[0].if_infeasible, trajectory_t::SHAPE);
  EXPECT_NE(r.out.find("corner 0.004 s, shaped if infeasible"), std::string::npos) << r.out;

  const fs::path csv = fs::temp_directory_path() / ("ctl_points_" + std::to_string(::getpid()) + ".csv");
  std::ofstream(csv) << "t_s,y_m\n0,0\n0.25,1e-6\n0.5,-1e-6\n";
  got.clear();
  r = run_ctl(with_url({"trajectory", "--shape", "points", "--points-csv", csv.string(), "--no-wait"}), lcm_.get());
  fs::remove(csv);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  ASSERT_EQ(got.size(), 3u);
  EXPECT_EQ(got[0].shape, trajectory_t::POINTS);
  ASSERT_EQ(got[0].n_points, 3);
  EXPECT_DOUBLE_EQ(got[0].points_t_s[1], 0.25);
  EXPECT_DOUBLE_EQ(got[0].points_y_m[2], -1e-6);
}

// ctl waits for the compensator's verdict on the version it sent: the test plays a compensator
// that reports on HX_STATUS right after each trajectory, as the real one does.
TEST_F(CtlLcmTest, TrajectoryWaitsForTheCompensatorsVerdict) {
  Publisher<service_status_t> status(*lcm_, ch_.status);
  enum class Answer { kAccept, kShape, kRefuse, kLater, kOldBuild, kSilent } answer = Answer::kAccept;
  std::int64_t accepted = 0, refused = 0, shaped = 0;
  std::string detail;
  Subscription<trajectory_t> sub(*lcm_, ch_.trajectory, [&](const trajectory_t& t, std::int64_t) {
    const std::string v = std::to_string(t.version);
    switch (answer) {
      case Answer::kAccept:
        accepted = t.version;
        detail = "trajectory " + v + " taken: as sent";
        break;
      case Answer::kShape:
        accepted = shaped = t.version;
        detail = "trajectory " + v + " shaped: amplitude 1e-06 m -> 5.09e-07 m (slew 9.8e4 V/s > 5e4 V/s)";
        break;
      case Answer::kRefuse:
        refused = t.version;
        detail = "trajectory " + v + " refused: slew 9.8e4 V/s > 5e4 V/s; at most 5.09e-07 m at 100 Hz";
        break;
      case Answer::kLater: accepted = t.version + 5; break;
      case Answer::kOldBuild:
      case Answer::kSilent: break;
    }
  });
  int ticks = 0;
  auto play_compensator = [&] {
    if (answer == Answer::kSilent || ++ticks % 10 != 0) return;  // every ~20 ms
    service_status_t s = status_of("compensator", service_status_t::HEALTHY);
    s.detail = detail;
    if (answer != Answer::kOldBuild) {
      s.counter_names = {"trajectory_version", "trajectory_refused_version", "trajectory_shaped_version"};
      s.counter_values = {accepted, refused, shaped};
      s.n_counters = 3;
    }
    status.publish(s);
  };
  const std::vector<std::string> sine{"trajectory", "--shape", "sine", "--amplitude", "1e-6", "--frequency", "100"};
  auto run = [&](Answer a, std::vector<std::string> extra = {}) {
    answer = a;
    std::vector<std::string> args = sine;
    args.insert(args.end(), extra.begin(), extra.end());
    return run_ctl(with_url(args), lcm_.get(), play_compensator);
  };

  Result r = run(Answer::kAccept);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("compensator accepted trajectory " + std::to_string(accepted) + ": as sent"), std::string::npos)
      << r.out;

  r = run(Answer::kShape, {"--shape-to-feasible"});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("shaped trajectory " + std::to_string(shaped) + ": amplitude 1e-06 m -> 5.09e-07 m"),
            std::string::npos)
      << r.out;

  r = run(Answer::kRefuse);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("refused trajectory " + std::to_string(refused) + ": slew 9.8e4 V/s > 5e4 V/s; at most"),
            std::string::npos)
      << r.err;

  r = run(Answer::kLater);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("before reporting on it"), std::string::npos) << r.err;

  // No verdict: bounded by --timeout, and the message says whether anyone answered at all.
  auto start = std::chrono::steady_clock::now();
  r = run(Answer::kSilent, {"--timeout", "0.5"});
  double took = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("no compensator confirmed trajectory version "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find(" within 0.5 s (no status from 'compensator'"), std::string::npos) << r.err;
  EXPECT_GE(took, 0.45);
  EXPECT_LT(took, 3.0);
  r = run(Answer::kOldBuild, {"--timeout", "0.5"});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("reports no trajectory_version"), std::string::npos) << r.err;
  // The default is 3 s; --no-wait returns at once.
  start = std::chrono::steady_clock::now();
  r = run(Answer::kSilent);
  took = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find(" within 3 s"), std::string::npos) << r.err;
  EXPECT_GE(took, 2.9);
  start = std::chrono::steady_clock::now();
  r = run(Answer::kSilent, {"--no-wait"});
  took = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_LT(took, 1.0);
}

TEST_F(CtlLcmTest, ParamsCarryTheValuesAndANewVersion) {
  std::vector<mem_params_t> got;
  Subscription<mem_params_t> sub(*lcm_, ch_.params, [&](const mem_params_t& p, std::int64_t) { got.push_back(p); });
  Result r = run_ctl(
      with_url({"params", "--c1", "1.2e-7", "--c2", "3e-9", "--c3", "0.8", "--version", "7", "--no-wait"}), lcm_.get());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  ASSERT_EQ(got.size(), 3u);
  EXPECT_EQ(got[0].version, 7);
  EXPECT_EQ(got[0].c1, 1.2e-7);
  EXPECT_EQ(got[0].c2, 3e-9);
  EXPECT_EQ(got[0].c3, 0.8);
  EXPECT_TRUE(got[0].valid);
  EXPECT_EQ(got[0].source, "hystloop-ctl");

  // Without --version: one above the version the rig uses (here: command ticks with v5, one v4).
  Publisher<command_block_t> commands(*lcm_, ch_.command);
  command_block_t cmd{};
  std::int64_t seq = 0;
  got.clear();
  r = run_ctl(with_url({"params", "--c1", "1e-7", "--c2", "0", "--c3", "1", "--listen", "0.5", "--no-wait"}),
              lcm_.get(), [&] {
                begin_block(cmd, seq, now_us(), seq - 1);
                for (int i = 0; i < 10; ++i, ++seq)
                  append_tick(cmd, {seq, 0.0, 0.0, i == 9 ? 4 : 5, command_block_t::MODE_MEM});
                commands.publish(cmd);
              });
  ASSERT_EQ(r.exit_code, 0) << r.err;
  ASSERT_FALSE(got.empty());
  EXPECT_EQ(got.back().version, 6);
}

TEST_F(CtlLcmTest, WaitHealthyTimesOutNamingWhoIsMissing) {
  const auto start = std::chrono::steady_clock::now();
  const Result r = run_ctl(with_url({"status", "--wait-healthy", "bridge", "compensator", "--timeout", "1"}));
  const double took = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("not healthy after 1 s"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("bridge: no status received"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("compensator: no status received"), std::string::npos) << r.err;
  EXPECT_GE(took, 0.9);
  EXPECT_LT(took, 5.0);
}

TEST_F(CtlLcmTest, WaitHealthyReturnsAsSoonAsEveryoneIsHealthy) {
  Publisher<service_status_t> status(*lcm_, ch_.status);
  int ticks = 0;
  auto play_rig = [&] {
    if (++ticks % 20 != 0) return;  // every ~40 ms
    status.publish(status_of("bridge", service_status_t::SAFE));
    status.publish(status_of("compensator", service_status_t::HEALTHY));
  };
  const auto start = std::chrono::steady_clock::now();
  Result r = run_ctl(
      with_url({"status", "--wait-healthy", "bridge", "compensator", "--accept-safe", "bridge", "--timeout", "10"}),
      lcm_.get(), play_rig);
  const double took = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_LT(took, 5.0);
  EXPECT_NE(r.out.find("bridge"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("SAFE"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("compensator"), std::string::npos) << r.out;

  // SAFE is not healthy unless accepted.
  r = run_ctl(with_url({"status", "--wait-healthy", "bridge", "--timeout", "0.5"}), lcm_.get(), play_rig);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("bridge: SAFE"), std::string::npos) << r.err;

  // Plain status lists what reported.
  r = run_ctl(with_url({"status", "--listen", "0.5"}), lcm_.get(), play_rig);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("HEALTHY"), std::string::npos) << r.out;
}

TEST_F(CtlLcmTest, WatchPrintsTheTrackingErrorOfTheSensorTicks) {
  Publisher<sensor_block_t> samples(*lcm_, ch_.sensor);
  Publisher<command_block_t> commands(*lcm_, ch_.command);
  Publisher<service_status_t> status(*lcm_, ch_.status);
  sensor_block_t s{};
  command_block_t c{};
  std::int64_t k = 0;
  int ticks = 0;
  auto play_rig = [&] {  // a block of 20 ticks every ~2 ms: about 10 kHz; error exactly 20 nm
    begin_block(s, k, now_us(), 1e-4);
    begin_block(c, k + 300, now_us(), k + 19);
    for (int i = 0; i < 20; ++i, ++k) {
      const double ref = 1e-6 * std::sin(0.001 * static_cast<double>(k));
      append_tick(s, {0, k, 0.0, 0.0, 0.0, i == 0 ? std::nan("") : ref, ref - 20e-9, 0});  // one without a reference
      append_tick(c, {k + 300, 0.0, ref, 3, command_block_t::MODE_MEM});
    }
    s.buffer_depth_ticks = 280 + static_cast<std::int32_t>(k % 7);
    samples.publish(s);
    commands.publish(c);
    if (++ticks % 100 == 0) {
      service_status_t b = status_of("bridge", service_status_t::HEALTHY, 7);
      b.counter_names = {"ticks", "clamped_per_s"};
      b.counter_values = {k, 12};
      b.n_counters = 2;
      status.publish(b);
      service_status_t comp = status_of("compensator", service_status_t::HEALTHY);
      comp.counter_names = {"learning_rms_pm", "learning_periods"};
      comp.counter_values = {7240, 3};
      comp.n_counters = 2;
      status.publish(comp);
    }
  };
  const Result r = run_ctl(with_url({"watch", "--seconds", "2.5"}), lcm_.get(), play_rig);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  std::vector<std::string> lines;
  std::istringstream in(r.out);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  ASSERT_EQ(lines.size(), 2u) << r.out;
  const std::string& last = lines.back();
  EXPECT_NE(last.find("rms    20.0 nm"), std::string::npos) << last;
  EXPECT_NE(last.find("max    20.0 nm"), std::string::npos) << last;
  EXPECT_NE(last.find("params v3"), std::string::npos) << last;
  EXPECT_NE(last.find("late 7"), std::string::npos) << last;
  EXPECT_NE(last.find("buf min 280 "), std::string::npos) << last;  // the lowest of 280 .. 286
  EXPECT_NE(last.find("clamped 12/s"), std::string::npos) << last;
  EXPECT_NE(last.find("learned 7.2 nm (3 periods)"), std::string::npos) << last;
}

// The series needs a running loop that is not in an experiment: both refusals name the cause.
TEST_F(CtlLcmTest, BanningSeriesRefusesWithoutCommandsOrWhileAnExperimentRuns) {
  Result r = run_ctl(with_url({"experiment", "--banning-series"}));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("no command on HX_COMMAND within 1 s"), std::string::npos) << r.err;

  Publisher<command_block_t> commands(*lcm_, ch_.command);
  std::vector<control_t> requests;
  Subscription<control_t> control(*lcm_, ch_.control, [&](const control_t& c, std::int64_t) { requests.push_back(c); });
  std::int64_t k = 0;
  command_block_t c{};
  auto experiment_running = [&] {
    begin_block(c, k, now_us(), k - 200);
    for (int i = 0; i < 10; ++i, ++k) append_tick(c, {k, 1.0, std::nan(""), 0, command_block_t::MODE_EXPERIMENT});
    commands.publish(c);
  };
  r = run_ctl(with_url({"experiment", "--banning-series"}), lcm_.get(), experiment_running);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("an experiment is running"), std::string::npos) << r.err;
  EXPECT_TRUE(requests.empty()) << "nothing may be sent";
}

// No LCM needed below: arguments are checked before the tool opens a connection.
TEST(CtlArguments, InvalidValuesExitTwoNamingTheField) {
  struct Case {
    std::vector<std::string> args;
    std::string must_say;
  };
  const std::vector<Case> cases{
      {{"params", "--c1", "-1", "--c2", "0", "--c3", "1"}, "c1: must be > 0 (got -1)"},
      {{"params", "--c1", "1e-7", "--c2", "-1e-9", "--c3", "1"}, "c2:"},
      {{"params", "--c1", "1e-7", "--c2", "0", "--c3", "0"}, "c3:"},
      {{"params", "--c1", "1e-7", "--c2", "0"}, "--c3"},
      {{"params", "--c1", "abc", "--c2", "0", "--c3", "1"}, "--c1"},
      {{"mode", "fast"}, "mode: unknown mode 'fast' (expected off, linear, mem, pi or katalenic)"},
      {{"gains", "--kp", "-0.1"}, "kp:"},
      {{"experiment", "--amplitude", "0", "--frequency", "1", "--duration", "1"}, "amplitude:"},
      {{"experiment", "--amplitude", "1", "--frequency", "1"}, "--duration"},
      {{"experiment", "--banning-series", "--amplitude", "3"}, "excludes"},
      {{"experiment", "--hysteresis-frequency", "4"}, "requires --banning-series"},
      {{"experiment", "--banning-series", "--hysteresis-frequency", "-1"}, "hysteresis_frequency_Hz: must be > 0"},
      {{"trajectory", "--shape", "square"}, "shape:"},
      {{"trajectory", "--shape", "sine", "--frequency", "0"}, "frequency:"},
      {{"trajectory", "--shape", "sine", "--blend", "-1"}, "blend:"},
      {{"trajectory", "--shape", "points"}, "points-csv:"},
      {{"trajectory"}, "shape:"},
      {{"trajectory", "--shape", "triangle", "--frequency", "10", "--corner", "0.05"},
       "corner: must be below half the period (0.05 s at 10 Hz"},
      {{"trajectory", "--shape", "triangle", "--corner", "-1"}, "corner:"},
      {{"trajectory", "--shape", "cosine", "--corner", "0.01"}, "corner: only for --shape triangle"},
      {{"trajectory", "--shape", "sine", "--timeout", "0"}, "timeout:"},
      {{"trajectory", "--shape", "sine", "--timeout", "1", "--no-wait"}, "excludes"},
      {{"gains", "--notch-hz", "5000", "--notch-q", "2"}, "notch-hz:"},
      {{"gains", "--notch-hz", "1700", "--notch-q", "0.05"}, "notch-q:"},
      {{"gains", "--notch-hz", "0", "--notch-q", "2"}, "notch-q: only with a notch"},
      {{"learn", "maybe"}, "learning: must be one of on|off|reset"},
      {{"learn"}, "what"},
      {{"status", "--wait-healthy", "bridge", "--timeout", "0"}, "timeout:"},
      {{"watch", "--seconds", "-1"}, "seconds:"},
      {{"frobnicate"}, "unknown command 'frobnicate' (one of: keygen, status"},
      {{}, "subcommand"},
      {{"--lcm-url", "udpm://239.255.76.67:7667?ttl=1", "arm"}, "lcm.url"},
  };
  for (const auto& c : cases) {
    const Result r = run_ctl(c.args);
    std::string joined;
    for (const auto& a : c.args) joined += a + " ";
    EXPECT_EQ(r.exit_code, 2) << joined << "\n" << r.err;
    EXPECT_NE(r.err.find(c.must_say), std::string::npos) << joined << "\nstderr: " << r.err;
  }
}

TEST(CtlArguments, HelpEverywhere) {
  const std::vector<std::pair<std::string, std::string>> subcommands{{"status", "--wait-healthy"},
                                                                     {"arm", "--target"},
                                                                     {"disarm", "--target"},
                                                                     {"shutdown", "process"},
                                                                     {"reset-counters", "process"},
                                                                     {"mode", "katalenic"},
                                                                     {"gains", "--notch-q"},
                                                                     {"learn", "reset"},
                                                                     {"experiment", "--duration"},
                                                                     {"stop-experiment", "--target"},
                                                                     {"trajectory", "--shape-to-feasible"},
                                                                     {"params", "--c3"},
                                                                     {"watch", "--compensator"}};
  Result r = run_ctl({"--help"});
  EXPECT_EQ(r.exit_code, 0);
  for (const auto& [name, option] : subcommands) {
    EXPECT_NE(r.out.find(name), std::string::npos) << name;
    const Result sub = run_ctl({name, "--help"});
    EXPECT_EQ(sub.exit_code, 0) << name << ": " << sub.err;
    EXPECT_NE(sub.out.find(option), std::string::npos) << name << ":\n" << sub.out;
  }
}
