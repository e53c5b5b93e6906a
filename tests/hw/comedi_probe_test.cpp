// hystloop-bridge itself against the fake card, loaded as libcomedi.so.0 from
// HYSTLOOP_FAKE_LIBCOMEDI_DIR: --probe-hardware lists the card and, with --yes only, drives the
// clamped triangle and reports the sensor's gain and sign; a config the card refuses exits 2
// with the output left safe; a SIGTERM leaves it safe (the fake logs the first and last DAC
// codes written at comedi_close: HX_FAKE_COMEDI_LOG).
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <initializer_list>
#include <string>

#include "support/text.hpp"

namespace {

const std::string kConfig = std::string(HYSTLOOP_SOURCE_DIR) + "/deploy/config/bridge-comedi.yaml";
const std::string kSafeCode = "first 32768 ";  // 0 V in [-10, 10] V, 16 bit

struct BridgeRun {
  int rc = -1;
  std::string out;
  std::string log;  // the fake's
};

using hystloop::testing::contains;
// Each of the texts is in the bridge's output (shown in full when one is not).
void expect_says(const BridgeRun& r, std::initializer_list<const char*> texts) {
  for (const char* text : texts) EXPECT_TRUE(contains(r.out, text)) << "no '" << text << "' in:\n" << r.out;
}

BridgeRun run(const std::string& fake, const std::string& args, const std::string& wrap = "",
              const std::string& config = kConfig) {
  const std::string log =
      ::testing::TempDir() + "/fake_comedi_" + ::testing::UnitTest::GetInstance()->current_test_info()->name() + ".log";
  std::remove(log.c_str());
  const std::string bridge = std::string(HYSTLOOP_BRIDGE_EXE) + " --config " + config + " " + args;
  const std::string cmd = "LD_LIBRARY_PATH=" HYSTLOOP_FAKE_LIBCOMEDI_DIR " HX_FAKE_COMEDI='" + fake +
                          "' HX_FAKE_COMEDI_LOG=" + log + " " + (wrap.empty() ? bridge : wrap + " '" + bridge + "'") +
                          " 2>&1";
  BridgeRun r;
  std::FILE* p = ::popen(cmd.c_str(), "r");
  if (p == nullptr) return r;
  std::array<char, 4096> buf{};
  while (std::fgets(buf.data(), buf.size(), p) != nullptr) r.out += buf.data();
  const int status = ::pclose(p);
  r.rc = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  std::ifstream f(log);
  std::stringstream ss;
  ss << f.rdbuf();
  r.log = ss.str();
  return r;
}

TEST(ComediProbe, ListsTheCardAndDrivesNothingWithoutYes) {
  const BridgeRun r = run("", "--probe-hardware");
  EXPECT_EQ(r.rc, 0) << r.out;
  expect_says(r, {"card: driver fake_driver, board fake_board, 3 subdevices",
                  "subdevice 0: analog input, 16 channels, maxdata 65535", "subdevice 1: analog output, 4 channels",
                  "    range 1: [0, 10] V", "calibration: none found (conversions use the range tables)",
                  "not driving the output. With --yes"});
  EXPECT_FALSE(contains(r.out, "measured"));
  EXPECT_TRUE(contains(r.log, "writes 0 ")) << r.log;
}

TEST(ComediProbe, WithYesReportsTheSensorsGainAndSign) {
  BridgeRun r = run("mirror_gain=0.5,calibration=1", "--probe-hardware --yes --duration-s 0.2");
  EXPECT_EQ(r.rc, 0) << r.out;
  expect_says(r, {"calibration: softcal file /var/lib/comedi/calibrations/fake_board_comedi0",
                  "comedi enable: subdevice 2 channel 0, a 500 Hz heartbeat active high",
                  "triangle 0 V -> 1 V -> -1 V -> 0 V at the card (x25: -25..25 V at the piezo)",
                  "measured: sensor +0.5", "verdict: sign OK"});
  // The amplifier enable beat during the drive (a write a step) and was dropped after it.
  EXPECT_TRUE(contains(r.log, " dio=0 outputs=1 ")) << r.log;
  const std::size_t at = r.log.rfind("dio_writes=");  // the drive's open (after the listing's)
  ASSERT_NE(at, std::string::npos) << r.log;
  EXPECT_GT(std::stol(r.log.substr(at + 11)), 200) << r.log;  // 0.2 s at 1 kHz, and the safe lists
  // The softcal code for 0 V (the fake's output is 2 mV high and 1 % steep): first and last.
  EXPECT_TRUE(contains(r.log, "first 32761 ") && contains(r.log, "last 32761 ")) << r.log;
  r = run("mirror_gain=-0.8", "--probe-hardware --yes --duration-s 0.2 --amplitude-V 2");
  EXPECT_EQ(r.rc, 1) << r.out;
  expect_says(r, {"measured: sensor -0.8", "SIGN REVERSED"});
  EXPECT_TRUE(contains(r.log, kSafeCode) && contains(r.log, "last 32768 ")) << r.log;
  // Clamped to the actuator's range: +-2 V at the card asked, +-50 V / 25 allowed.
  r = run("mirror_gain=1",
          "--probe-hardware --yes --duration-s 0.1 --amplitude-V 5 --set actuator.u_min_V=-50 "
          "--set actuator.u_max_V=50");
  EXPECT_TRUE(contains(r.out, "triangle 0 V -> 2 V -> -2 V -> 0 V")) << r.out;
}

TEST(ComediProbe, ACardThatRefusesTheConfigExitsTwoWithTheOutputSafe) {
  // +-250 V through a gain of 10: +-25 V at the card, beyond its +-10 V.
  BridgeRun r = run("",
                    "--probe-hardware --yes --set comedi.amplifier_gain_V_per_V=10 --set actuator.u_min_V=-250 "
                    "--set actuator.u_max_V=250");
  EXPECT_EQ(r.rc, 2) << r.out;
  EXPECT_TRUE(contains(r.out, "comedi.ao.range")) << r.out;
  EXPECT_TRUE(contains(r.log, "writes 1 first 32768 ")) << r.log;
  r = run("", "--probe-hardware --yes --set comedi.ai.channel=40");
  EXPECT_EQ(r.rc, 2) << r.out;
  EXPECT_TRUE(contains(r.out, "comedi.ai.channel")) << r.out;
  r = run("", "--probe-hardware --device /dev/nothing");
  EXPECT_EQ(r.rc, 1) << r.out;
  EXPECT_TRUE(contains(r.out, "comedi_open(/dev/nothing)")) << r.out;
}

TEST(ComediProbe, SigtermLeavesTheOutputSafe) {
  const std::string netns = std::string(HYSTLOOP_SOURCE_DIR) + "/tools/netns-run --keyless";
  const BridgeRun r = run(
      "",
      "--set rt.priority=0 --set rt.io_priority=0 --set rt.lock_memory=false --set rt.cpu=-1 --set rt.required=false",
      netns + " -- sh -c '$0 & pid=$!; sleep 1; kill -TERM $pid; wait $pid'");
  EXPECT_EQ(r.rc, 0) << r.out;
  expect_says(r, {"the safe 0 V written (DAC code 32768)", "stopping on signal 15"});
  EXPECT_TRUE(contains(r.log, kSafeCode) && contains(r.log, "last 32768 ")) << r.log;
  EXPECT_TRUE(contains(r.log, " dio=0 outputs=1 ")) << r.log;  // the enable: an output, never active unarmed
}

// A card needs real time: where the host refuses SCHED_FIFO (no CAP_SYS_NICE, rtprio 0: here made
// so on purpose) the bridge never arms, goes down through the safe state and exits 1 naming how to
// grant it; waived (rt.required: false) it runs, saying it was refused.
TEST(ComediProbe, ABridgeRefusedRealTimeStopsSafelyNamingTheFix) {
  const std::string netns = std::string(HYSTLOOP_SOURCE_DIR) + "/tools/netns-run --keyless";
  // setpriv drops the capability (as root; a user has none to drop), prlimit the rtprio limit.
  const std::string unprivileged =
      "if [ \"$(id -u)\" = 0 ]; then exec prlimit --rtprio=0 setpriv --bounding-set -sys_nice -- $0; "
      "else exec prlimit --rtprio=0 $0; fi";
  const std::string rt = "--set rt.cpu=-1 --set rt.lock_memory=false ";
  BridgeRun r = run("", rt, netns + " -- sh -c '" + unprivileged + "'");
  EXPECT_EQ(r.rc, 2) << r.out;  // without locked memory the config itself is refused
  expect_says(r, {"rt.required", "rt.lock_memory: true"});
  r = run("", "--set rt.cpu=-1", netns + " -- sh -c '" + unprivileged + "'");
  EXPECT_EQ(r.rc, 1) << r.out;
  expect_says(r, {"rt.required: SCHED_FIFO priority 80", "setcap cap_sys_nice,cap_ipc_lock+ep", "rt.required: false",
                  "safe state reached"});
  EXPECT_TRUE(contains(r.log, kSafeCode) && contains(r.log, "last 32768 ")) << r.log;
  r = run("", "--set rt.cpu=-1 --set rt.required=false",
          netns + " -- sh -c '" + unprivileged + " & pid=$!; sleep 1; kill -TERM $pid; wait $pid'");
  EXPECT_EQ(r.rc, 0) << r.out;
  expect_says(r, {"SCHED_FIFO priority 80", "not required", "stopping on signal 15"});
}

// The latency test runs the card's real tick, never armed: the output at its safe code from the
// first write to the last; the figures and the verdict printed, the exit status the verdict's
// (either may come out on a shared machine: the test checks they agree, not the machine).
TEST(ComediProbe, TheLatencyTestRunsTheCardsTickAtTheSafeVoltageAndGivesAVerdict) {
  const BridgeRun r = run("", "--latency-test 1 --set rt.cpu=-1");
  ASSERT_TRUE(r.rc == 0 || r.rc == 1) << r.out;
  expect_says(r, {"latency test: comedi backend, 10000 Hz", "timer wake-up lateness over", "p99.9",
                  "1.0 us ..    2.0 us", "longer", "tick work", "ticks skipped:", "verdict: "});
  EXPECT_TRUE(contains(r.out, r.rc == 0 ? "verdict: fit to arm" : "verdict: NOT fit to arm")) << r.out;
  EXPECT_TRUE(contains(r.log, kSafeCode) && contains(r.log, "last 32768 ")) << r.log;
  // The simulator's tick too (its wake-ups run rt.ticks_per_wake ticks each).
  const BridgeRun sim =
      run("", "--latency-test 0.5", "", std::string(HYSTLOOP_SOURCE_DIR) + "/deploy/config/bridge.yaml");
  ASSERT_TRUE(sim.rc == 0 || sim.rc == 1) << sim.out;
  expect_says(sim, {"latency test: sim backend, 10000 Hz", "wake-ups (50 tick(s) each)",
                    "verdict: ", "the verdict is a card's host's"});
}

// Three axes, each on its own channel pair, y with a safe voltage of its own: the binary starts
// every output at its safe code and a SIGTERM leaves each there (the fake's log: what each output
// holds at comedi_close, and how many writes it had).
TEST(ComediProbe, SigtermLeavesEveryAxissOutputSafe) {
  const std::string netns = std::string(HYSTLOOP_SOURCE_DIR) + "/tools/netns-run --keyless";
  const BridgeRun r = run(
      "mirror_by_channel=1",
      "--set bridge.axes=3 --set comedi.y.ao.channel=1 --set comedi.y.ai.channel=1 "
      "--set comedi.z.ao.channel=2 --set comedi.z.ai.channel=2 --set actuator.y.safe_u_V=25 "
      "--set rt.priority=0 --set rt.io_priority=0 --set rt.lock_memory=false --set rt.cpu=-1 --set rt.required=false",
      netns + " -- sh -c '$0 & pid=$!; sleep 1; kill -TERM $pid; wait $pid'");
  EXPECT_EQ(r.rc, 0) << r.out;
  // 25 V / 25 = 1 V at the card: code 36044 of [-10, 10] V.
  expect_says(r, {"comedi: the safe voltages written: x 0 V (DAC code 32768), y 25 V (DAC code 36044), z 0 V",
                  "stopping on signal 15"});
  for (const char* holds : {" ao0=32768/", " ao1=36044/", " ao2=32768/", " ao3=0/0"}) {
    EXPECT_TRUE(contains(r.log, holds)) << holds << " not in " << r.log;
  }
  EXPECT_FALSE(contains(r.log, " ao0=32768/1 ")) << "the loop never wrote: " << r.log;
}

}  // namespace
