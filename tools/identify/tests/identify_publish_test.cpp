// hystloop-identify --publish against real udpm LCM (ttl=0) inside tools/netns-run: the test
// subscribes to HX_PARAMS and HX_MODEL, runs the tool on a recorded log as a child process, keeps
// dispatching (and, where needed, plays a rig whose parameter set in use has a version, or a
// compensator that reports on HX_STATUS the version it uses) until the child exits, then checks
// what arrived -- the fitted values, valid = true, the version, the signature on a keyed rig --
// and what the tool said of the adoption.
#include <gtest/gtest.h>

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <regex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "hystloop/command_block_t.hpp"
#include "hystloop/model_params_t.hpp"
#include "hystloop/service_status_t.hpp"
#include "lcm/blocks.hpp"
#include "lcm/channels.hpp"
#include "lcm/connection.hpp"
#include "lcm/publisher.hpp"
#include "lcm/rig_auth.hpp"
#include "lcm/subscription.hpp"
#include "sensor_log_fixture.hpp"

extern char** environ;

namespace hystloop {
namespace {

namespace fs = std::filesystem;
using namespace testlog;

const std::string kUrl = "udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304";

struct Result {
  int exit_code = -1;
  std::string out;
};

std::string slurp(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// Runs the tool; while it runs, dispatches `lcm` and calls tick() every ~2 ms.
Result run_tool(const std::vector<std::string>& args, lcm::LCM& lcm, const std::function<void()>& tick = {}) {
  const fs::path out = fs::temp_directory_path() / ("identify_publish_out_" + std::to_string(::getpid()));
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 1, out.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&actions, 1, 2);
  std::vector<std::string> all{HYSTLOOP_IDENTIFY_EXE};
  all.insert(all.end(), args.begin(), args.end());
  std::vector<char*> argv;
  argv.reserve(all.size() + 1);
  for (auto& a : all) argv.push_back(a.data());
  argv.push_back(nullptr);
  Result r;
  pid_t pid = 0;
  const int spawned = posix_spawn(&pid, HYSTLOOP_IDENTIFY_EXE, &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (spawned != 0) return r;
  int status = 0;
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while (::waitpid(pid, &status, WNOHANG) != pid) {
    if (std::chrono::steady_clock::now() > give_up) {
      ::kill(pid, SIGKILL);
      ::waitpid(pid, &status, 0);
      break;
    }
    handle_pending(lcm, std::chrono::microseconds(2000));
    if (tick) tick();
  }
  handle_pending(lcm, std::chrono::microseconds(50'000));  // stragglers
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = slurp(out);
  fs::remove(out);
  return r;
}

class IdentifyPublish : public ::testing::Test {
 protected:
  void SetUp() override {
    if (std::getenv("HYSTLOOP_NETNS") == nullptr) GTEST_SKIP() << "needs udpm LCM: run inside tools/netns-run";
    dir_ = fs::temp_directory_path() / ("hystloop_identify_publish_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
    lcm_ = open_lcm(kUrl);
    params_ =
        std::make_unique<Subscription<mem_params_t>>(*lcm_, ch_.params, [this](const mem_params_t& m, std::int64_t) {
          if (m.source.rfind("hystloop-identify@", 0) == 0) received_.push_back(m);
        });
    models_ =
        std::make_unique<Subscription<model_params_t>>(*lcm_, ch_.model, [this](const model_params_t& m, std::int64_t) {
          if (m.source.rfind("hystloop-identify@", 0) == 0) models_received_.push_back(m);
        });
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  // Fire and forget (--no-wait): no compensator runs in these tests unless one is played.
  std::vector<std::string> args(const std::string& log, std::vector<std::string> more) const {
    std::vector<std::string> a{log, "--model", "mem", "--publish", "--lcm-url", kUrl, "--no-wait"};
    a.insert(a.end(), more.begin(), more.end());
    return a;
  }

  fs::path dir_;
  ChannelNames ch_;
  std::unique_ptr<lcm::LCM> lcm_;
  std::unique_ptr<Subscription<mem_params_t>> params_;
  std::vector<mem_params_t> received_;
  std::unique_ptr<Subscription<model_params_t>> models_;
  std::vector<model_params_t> models_received_;
  const MemParams truth_ = MemParams::paper_like();
};

double printed(const std::string& out, const std::string& name) {
  std::smatch m;
  if (!std::regex_search(out, m, std::regex(name + R"( ([-+0-9.eE]+))"))) return -1.0;
  return std::stod(m[1].str());
}

TEST_F(IdentifyPublish, FittedSetArrivesOnHxParamsWithTheNextVersion) {
  write_log(path("run.lcmlog"), with_faults(mem_record(truth_, 0.5e-9)));
  const Result r = run_tool(args(path("run.lcmlog"), {}), *lcm_);
  ASSERT_EQ(r.exit_code, 0) << r.out;
  EXPECT_NE(r.out.find("no parameter version heard"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("published MEM parameters v2 on HX_PARAMS (3 time(s))"), std::string::npos) << r.out;
  ASSERT_GE(received_.size(), 1u) << r.out;  // sent 3 times; UDP inside one host should keep all
  EXPECT_LE(received_.size(), 3u);
  for (const auto& m : received_) {
    EXPECT_EQ(m.version, 2);
    // The run's own publisher id (versions are ordered per publisher), the same on every repeat.
    EXPECT_NE(m.publisher_id, 0);
    EXPECT_EQ(m.publisher_id, received_.front().publisher_id);
    EXPECT_TRUE(m.valid);
    EXPECT_NEAR(m.c1, truth_.c1, 0.01 * truth_.c1);
    EXPECT_NEAR(m.c2, truth_.c2, 0.01 * truth_.c2);
    EXPECT_NEAR(m.c3, truth_.c3, 0.01 * truth_.c3);
    // The values printed are the values sent (to the printed precision).
    EXPECT_NEAR(m.c1, printed(r.out, "c1"), 1e-5 * m.c1);
    EXPECT_NEAR(m.c3, printed(r.out, "c3"), 1e-5 * m.c3);
    EXPECT_GT(m.samples_used, 15'000);
    EXPECT_LE(m.samples_used, static_cast<std::int64_t>(kTicks));
    EXPECT_NEAR(m.window_s, 1.9999, 1e-9);
    EXPECT_GT(m.residual_m, 0.0);
    EXPECT_LT(m.residual_m, 2e-9);
    EXPECT_GT(m.utime, kFirstUtime);
  }
}

TEST_F(IdentifyPublish, VersionSupersedesTheSetInUse) {
  write_log(path("run.lcmlog"), mem_record(truth_));
  // A rig whose compensator uses v6 (in its commands) and whose re-identifier sent v7.
  Publisher<mem_params_t> params(*lcm_, ch_.params);
  Publisher<command_block_t> commands(*lcm_, ch_.command);
  mem_params_t in_use{};
  in_use.version = 7;
  in_use.c1 = 4e-9;
  in_use.c3 = 1.0;
  in_use.valid = true;
  in_use.source = "reident@test";
  command_block_t cmd{};
  begin_block(cmd, 0, kFirstUtime, -1);
  for (std::int64_t k = 0; k < 10; ++k) append_tick(cmd, {k, 0.0, 0.0, k == 9 ? 5 : 6, command_block_t::MODE_MEM});
  int ticks = 0;
  const Result r = run_tool(args(path("run.lcmlog"), {"--listen-s", "0.3"}), *lcm_, [&] {
    commands.publish(cmd);
    if (++ticks % 25 == 0) params.publish(in_use);
  });
  ASSERT_EQ(r.exit_code, 0) << r.out;
  EXPECT_NE(r.out.find("version in use on HX_: 7"), std::string::npos) << r.out;
  ASSERT_GE(received_.size(), 1u) << r.out;
  EXPECT_EQ(received_.front().version, 8);

  // Only the commands: a compensator does not repeat HX_PARAMS, its command ticks carry the version.
  received_.clear();
  const Result c = run_tool(args(path("run.lcmlog"), {"--listen-s", "0.3"}), *lcm_, [&] { commands.publish(cmd); });
  ASSERT_EQ(c.exit_code, 0) << c.out;
  ASSERT_GE(received_.size(), 1u) << c.out;
  EXPECT_EQ(received_.front().version, 7);

  // --version wins, nothing is listened for; another rig's channels from --rig.
  received_.clear();
  write_log(path("rig3.lcmlog"), mem_record(truth_), 0, kTicks, false, "RIG3_SENSOR");
  std::vector<mem_params_t> rig3;
  Subscription<mem_params_t> rig3_params(*lcm_, "RIG3_PARAMS",
                                         [&](const mem_params_t& m, std::int64_t) { rig3.push_back(m); });
  const Result v = run_tool(args(path("rig3.lcmlog"), {"--version", "42", "--rig", "RIG3_"}), *lcm_);
  ASSERT_EQ(v.exit_code, 0) << v.out;
  EXPECT_NE(v.out.find("published MEM parameters v42 on RIG3_PARAMS"), std::string::npos) << v.out;
  EXPECT_TRUE(received_.empty()) << "published on HX_PARAMS although --rig RIG3_";
  ASSERT_GE(rig3.size(), 1u);
  EXPECT_EQ(rig3.front().version, 42);
  EXPECT_NEAR(rig3.front().c2, truth_.c2, 0.01 * truth_.c2);
}

// A URL whose packets could leave the host (ttl > 0) is refused before the fit, from a log or a
// CSV, and nothing is sent. Inside this namespace such packets could not leave anyway; they would
// reach the test's own subscription on the same group and port, which must stay silent.
TEST_F(IdentifyPublish, AUrlThatCouldLeaveTheHostIsRefusedBeforeTheFit) {
  const auto record = mem_record(truth_);
  write_log(path("run.lcmlog"), record);
  {
    std::ofstream csv(path("run.csv"));
    csv << "t,u,y\n";
    for (const auto& s : record) {
      csv << static_cast<double>(s.seq - record.front().seq) * 1e-4 << "," << s.u_V << "," << s.y_m << "\n";
    }
  }
  for (const std::string input : {"run.lcmlog", "run.csv"}) {
    const Result r = run_tool(
        {path(input), "--model", "mem", "--publish", "--lcm-url", "udpm://239.255.76.67:7667?ttl=1", "--listen-s", "0"},
        *lcm_);
    EXPECT_EQ(r.exit_code, 2) << input << ": " << r.out;
    EXPECT_NE(r.out.find("lcm.url"), std::string::npos) << r.out;
    EXPECT_EQ(r.out.find("mem: c1 "), std::string::npos) << "fitted before the URL was checked: " << r.out;
  }
  EXPECT_TRUE(received_.empty());
}

TEST_F(IdentifyPublish, RefusedFitPublishesNothing) {
  auto record = mem_record(truth_);
  for (auto& s : record) {
    s.u_V = 5.0;
    s.y_m = 1e-9;
  }
  write_log(path("flat.lcmlog"), record);
  const Result r = run_tool(args(path("flat.lcmlog"), {"--listen-s", "0"}), *lcm_);
  EXPECT_EQ(r.exit_code, 1) << r.out;
  EXPECT_NE(r.out.find("constant_input"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("nothing published"), std::string::npos) << r.out;
  EXPECT_TRUE(received_.empty());
}

// Any model goes out on HX_MODEL as model_params_t: its kind and the values printed, the next
// version, valid, the stage left to the receiver. --model mem too when asked (--publish-on model).
TEST_F(IdentifyPublish, AnyModelArrivesOnHxModelWithTheFittedValues) {
  write_log(path("run.lcmlog"), mem_record(truth_, 0.5e-9));
  const Result r = run_tool(
      {path("run.lcmlog"), "--model", "linear", "--publish", "--lcm-url", kUrl, "--no-wait", "--listen-s", "0.1"},
      *lcm_);
  ASSERT_EQ(r.exit_code, 0) << r.out;
  EXPECT_NE(r.out.find("published linear parameters v2 on HX_MODEL (3 time(s))"), std::string::npos) << r.out;
  EXPECT_TRUE(received_.empty()) << "a linear set on HX_PARAMS";
  ASSERT_GE(models_received_.size(), 1u) << r.out;
  double gain = 0.0, offset = 0.0;
  ASSERT_EQ(std::sscanf(r.out.substr(r.out.find("linear: gain ")).c_str(), "linear: gain %lf m/V, offset %lf m", &gain,
                        &offset),
            2)
      << r.out;
  for (const auto& m : models_received_) {
    EXPECT_EQ(m.kind, model_params_t::KIND_LINEAR);
    EXPECT_EQ(m.format_version, model_params_t::FORMAT_VERSION);
    EXPECT_EQ(m.version, 2);
    EXPECT_NE(m.publisher_id, 0);
    EXPECT_TRUE(m.valid);
    EXPECT_EQ(m.stage_kind, model_params_t::STAGE_UNCHANGED);
    EXPECT_NEAR(m.linear_gain, gain, 1e-5 * std::abs(gain));
    EXPECT_NEAR(m.linear_offset_m, offset, 1e-5 * std::abs(offset) + 1e-15);
    EXPECT_GT(m.residual_m, 0.0);
    EXPECT_GT(m.samples_used, 15'000);
    EXPECT_NEAR(m.window_s, 1.9999, 1e-9);
  }

  models_received_.clear();
  const Result mem = run_tool(args(path("run.lcmlog"), {"--publish-on", "model", "--version", "9"}), *lcm_);
  ASSERT_EQ(mem.exit_code, 0) << mem.out;
  EXPECT_NE(mem.out.find("published mem parameters v9 on HX_MODEL"), std::string::npos) << mem.out;
  ASSERT_GE(models_received_.size(), 1u) << mem.out;
  EXPECT_EQ(models_received_.front().kind, model_params_t::KIND_MEM);
  EXPECT_NEAR(models_received_.front().mem_c1, truth_.c1, 0.01 * truth_.c1);
  EXPECT_NEAR(models_received_.front().mem_c2, truth_.c2, 0.01 * truth_.c2);
  EXPECT_NEAR(models_received_.front().mem_c3, truth_.c3, 0.01 * truth_.c3);
  EXPECT_NEAR(models_received_.front().mem_c3, printed(mem.out, "c3"), 1e-5 * truth_.c3);
}

// On a keyed rig the set is signed with the rig key: a receiver holding the key takes it.
TEST_F(IdentifyPublish, OnAKeyedRigTheSetIsSigned) {
  write_log(path("run.lcmlog"), mem_record(truth_, 0.5e-9));
  {
    std::ofstream key(path("rig.key"));
    key << "000102030405060708090a0b0c0d0e0f101112131415161718191a1b1c1d1e1f\n";
  }
  fs::permissions(path("rig.key"), fs::perms::owner_read | fs::perms::owner_write, fs::perm_options::replace);
  Subscription<model_params_t>::Options keyed;
  keyed.auth = rig_auth_from_key_file(path("rig.key"), "key");
  std::vector<model_params_t> verified;
  Subscription<model_params_t> signed_models(
      *lcm_, ch_.model, [&](const model_params_t& m, std::int64_t) { verified.push_back(m); }, keyed);
  ASSERT_TRUE(signed_models.authenticated());
  const Result r = run_tool({path("run.lcmlog"), "--model", "pi", "--publish", "--lcm-url", kUrl, "--no-wait",
                             "--listen-s", "0.1", "--key-file", path("rig.key")},
                            *lcm_);
  ASSERT_EQ(r.exit_code, 0) << r.out;
  ASSERT_GE(verified.size(), 1u) << r.out;
  EXPECT_EQ(verified.front().kind, model_params_t::KIND_PI);
  EXPECT_EQ(verified.front().n_operators, 15);
  EXPECT_EQ(signed_models.counters().rejected_total(), 0u);

  // Unsigned, the same receiver refuses it.
  verified.clear();
  const Result u = run_tool(
      {path("run.lcmlog"), "--model", "pi", "--publish", "--lcm-url", kUrl, "--no-wait", "--listen-s", "0.1"}, *lcm_);
  ASSERT_EQ(u.exit_code, 0) << u.out;
  EXPECT_TRUE(verified.empty());
  EXPECT_GE(signed_models.counters().rejected(RejectReason::kUnsigned), 1u);
}

// A compensator played here: it reports on HX_STATUS, 50 times a second, the version it uses in
// the counter "params_version"; with `adopts` it takes the first set from the tool on HX_MODEL.
struct FakeCompensator {
  FakeCompensator(lcm::LCM& lcm, const ChannelNames& ch, std::string name, bool adopts)
      : status(lcm, ch.status), process(std::move(name)) {
    if (adopts) {
      models = std::make_unique<Subscription<model_params_t>>(
          lcm, ch.model, [this](const model_params_t& m, std::int64_t) { in_use = m.version; });
    }
  }
  void tick() {
    if (++ticks % 10 != 0) return;
    service_status_t s{};
    s.utime = kFirstUtime;
    s.process = process;
    s.host = "test";
    s.pid = 4242;
    s.state = service_status_t::HEALTHY;
    s.n_counters = 2;
    s.counter_names = {"params_version", "samples"};
    s.counter_values = {in_use, 100};
    s.loop_p50_us = s.loop_p99_us = s.loop_max_us = std::nan("");
    s.latency_p50_us = s.latency_p99_us = s.latency_max_us = std::nan("");
    status.publish(s);
  }
  Publisher<service_status_t> status;
  std::unique_ptr<Subscription<model_params_t>> models;
  std::string process;
  std::int64_t in_use = 1;
  int ticks = 0;
};

TEST_F(IdentifyPublish, AdoptedWhenTheCompensatorReportsTheVersionInUse) {
  write_log(path("run.lcmlog"), mem_record(truth_, 0.5e-9));
  FakeCompensator comp(*lcm_, ch_, "compensator", true);
  const Result r = run_tool({path("run.lcmlog"), "--model", "mem", "--publish-on", "model", "--publish", "--lcm-url",
                             kUrl, "--version", "5", "--timeout", "10"},
                            *lcm_, [&] { comp.tick(); });
  ASSERT_EQ(r.exit_code, 0) << r.out;
  EXPECT_NE(r.out.find("adopted by 'compensator' (version 5)"), std::string::npos) << r.out;
  EXPECT_EQ(comp.in_use, 5);
}

TEST_F(IdentifyPublish, NotAdoptedNamesTheCompensatorAndTheVersionItUses) {
  write_log(path("run.lcmlog"), mem_record(truth_, 0.5e-9));
  FakeCompensator comp(*lcm_, ch_, "compensator", false);  // hears nothing: keeps v1
  const Result r = run_tool({path("run.lcmlog"), "--model", "katalenic", "--publish", "--lcm-url", kUrl, "--version",
                             "5", "--timeout", "0.5"},
                            *lcm_, [&] { comp.tick(); });
  EXPECT_EQ(r.exit_code, 1) << r.out;
  EXPECT_NE(r.out.find("published katalenic parameters v5 on HX_MODEL"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("not adopted within 0.5 s ('compensator' in use: version 1)"), std::string::npos) << r.out;
  ASSERT_GE(models_received_.size(), 1u);
  EXPECT_EQ(models_received_.front().kind, model_params_t::KIND_KATALENIC);

  // Another process reports, the compensator does not (--compensator names the one that counts).
  FakeCompensator bridge(*lcm_, ch_, "bridge", false);
  const Result b = run_tool({path("run.lcmlog"), "--model", "linear", "--publish", "--lcm-url", kUrl, "--timeout",
                             "0.5", "--compensator", "comp2", "--listen-s", "0.1"},
                            *lcm_, [&] { bridge.tick(); });
  EXPECT_EQ(b.exit_code, 1) << b.out;
  EXPECT_NE(b.out.find("not adopted within 0.5 s (no 'comp2' reported on HX_STATUS; heard: bridge)"), std::string::npos)
      << b.out;
}

TEST_F(IdentifyPublish, NothingOnHxStatusMeansNoRigIsRunning) {
  write_log(path("run.lcmlog"), mem_record(truth_, 0.5e-9));
  const Result r = run_tool(
      {path("run.lcmlog"), "--model", "mem", "--publish", "--lcm-url", kUrl, "--listen-s", "0.1", "--timeout", "0.3"},
      *lcm_);
  EXPECT_EQ(r.exit_code, 1) << r.out;
  EXPECT_NE(r.out.find("published MEM parameters v2 on HX_PARAMS"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("no rig is running (nothing reported on HX_STATUS within 0.3 s)"), std::string::npos) << r.out;
}

}  // namespace
}  // namespace hystloop
