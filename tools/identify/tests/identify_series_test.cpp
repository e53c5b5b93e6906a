// Banning's series from a live loop's log: the requests hystloop-ctl sends (its banning_series),
// run by the real Compensator (planning ahead, in blocks) against the simulated Banning stage
// tick by tick, recorded as the logger would (HX_CONTROL, HX_COMMAND and HX_SENSOR blocks) with
// lcm::LogFile. The splitter must find every experiment at the ticks the compensator ran it,
// label settling, find a stopped series, a request missing from the log and samples missing
// from it; the tool must fit the stage back.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <complex>
#include <cstdio>
#include <filesystem>
#include <numbers>
#include <regex>
#include <set>
#include <string>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "ctl_requests.hpp"
#include "ctl_series.hpp"
#include "hystloop/command_block_t.hpp"
#include "hystloop/control_t.hpp"
#include "hystloop/sensor_block_t.hpp"
#include "lcm/blocks.hpp"
#include "lcm/message_storage.hpp"
#include "log_experiments.hpp"
#include "log_samples.hpp"
#include "loop/compensator.hpp"
#include "loop/simulated_stage.hpp"
#include "models/second_order_stage.hpp"
#include "sensor_log_fixture.hpp"
#include "support/tool_run.hpp"

namespace hystloop {
namespace {

using testlog::encoded;
using testlog::write_event;

constexpr std::int64_t kFirstSeq = 5000;
constexpr std::int64_t kRequestTick = kFirstSeq + 300;  // the requests arrive 30 ms into the record
constexpr std::int64_t kUtime0 = 1'700'000'000'000'000;

// A short series: two offsets, a small and two large amplitudes at 5 Hz, four frequencies.
BanningPlanOptions short_plan() {
  BanningPlanOptions p;
  p.offsets_V = {-60.0, 60.0};
  p.small_amplitudes_V = {2.0};
  p.amplitudes_V = {50.0, 120.0};
  p.hysteresis_frequency_Hz = 5.0;
  p.frequencies_Hz = {300.0, 1200.0, 1700.0, 2400.0};
  return p;
}

struct Faults {
  std::set<std::size_t> requests_not_logged;  // the compensator got them, the log did not
  std::int64_t stop_at_tick = -1;             // STOP_EXPERIMENT at this tick
  std::int64_t drop_samples_from = -1;        // ticks [from, from + count) not recorded
  std::int64_t drop_samples_count = 0;
  std::int64_t late_from = -1;  // ticks [from, from + count) flagged LATE_COMMAND
  std::int64_t late_count = 0;
};

struct Recording {
  std::vector<ExperimentSpec> specs;  // as sent
  std::int64_t first_experiment_tick = -1;
};

// The loop: the bridge sends a sensor block every kBlockTicks ticks; the compensator observes
// it and answers with the command ticks it plans up to its horizon ahead, each tick once; the
// bridge applies the command of each tick (no servo: every tick here has no reference or gains
// of zero), holding the last one when none arrived.
constexpr std::int64_t kBlockTicks = 10;

Recording record_series(const std::string& path, const std::vector<ctl::SeriesStep>& steps, const Faults& faults,
                        double seconds) {
  Recording rec;
  lcm::LogFile log(path, "w");
  EXPECT_TRUE(log.good());
  std::int64_t eventnum = 0;
  SimulatedStageConfig sc;
  sc.noise_rms_m = 0.5e-9;
  SimulatedStage stage(sc);
  CompensatorConfig cc;
  cc.mode = FeedforwardMode::kOff;
  Compensator comp(cc);
  std::array<CommandTick, 16'384> buffer{};  // the bridge's jitter buffer, by tick
  for (auto& c : buffer) c.seq = -1;
  std::array<CommandTick, command_block_t::MAX_TICKS> planned{};
  std::vector<SensorTick> block;  // the ticks of the block being sampled
  sensor_block_t sensor{};
  command_block_t command{};
  reserve_storage(sensor);
  reserve_storage(command);
  CommandTick held{};
  // Logs ticks [first, last) of `block` as one HX_SENSOR block.
  auto log_sensor = [&](std::size_t first, std::size_t last) {
    if (first == last) return;
    begin_block(sensor, block[first].seq, block[first].utime, cc.dt_s);
    for (std::size_t i = first; i < last; ++i) append_tick(sensor, block[i]);
    sensor.buffer_depth_ticks = 200;
    write_event(log, eventnum, block[last - 1].utime, "HX_SENSOR", encoded(sensor));
  };
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
    if (seq >= faults.late_from && seq < faults.late_from + faults.late_count) s.flags |= sensor_block_t::LATE_COMMAND;
    block.push_back(s);
    if (seq == kRequestTick) {
      for (std::size_t i = 0; i < steps.size(); ++i) {
        control_t c{};
        c.utime = utime;
        c.request_id = 7000 + static_cast<std::int64_t>(i);
        c.command = control_t::START_EXPERIMENT;
        ctl::apply(steps[i].request, c);  // as hystloop-ctl puts it on the wire
        if (!faults.requests_not_logged.contains(i)) {
          write_event(log, eventnum, utime, "HX_CONTROL", encoded(c));
          write_event(log, eventnum, utime, "HX_CONTROL", encoded(c));  // ctl repeats a request
        }
        rec.specs.push_back(ctl::to_spec(steps[i].request));
        comp.start_experiment(rec.specs.back());
      }
    }
    if (seq == faults.stop_at_tick) {
      control_t c{};
      c.utime = utime;
      c.request_id = 9999;
      c.command = control_t::STOP_EXPERIMENT;
      write_event(log, eventnum, utime, "HX_CONTROL", encoded(c));
      comp.stop_experiment();
    }
    if (static_cast<std::int64_t>(block.size()) < kBlockTicks) continue;
    // The block goes out; the logger records what was not dropped.
    std::size_t run = 0;
    for (std::size_t i = 0; i < block.size(); ++i) {
      const std::int64_t k = block[i].seq;
      if (k >= faults.drop_samples_from && k < faults.drop_samples_from + faults.drop_samples_count) {
        log_sensor(run, i);
        run = i + 1;
      }
    }
    log_sensor(run, block.size());
    for (const auto& b : block) comp.observe({b.seq, b.u_V, b.y_m});
    block.clear();
    // The compensator answers with the ticks it has not sent yet.
    while (const std::size_t n = comp.plan(planned)) {
      begin_block(command, planned[0].seq, utime + 20, comp.last_seq());
      for (std::size_t i = 0; i < n; ++i) {
        append_tick(command, planned[i]);
        buffer[static_cast<std::size_t>(planned[i].seq) % buffer.size()] = planned[i];
        if (planned[i].mode == command_block_t::MODE_EXPERIMENT && rec.first_experiment_tick < 0) {
          rec.first_experiment_tick = planned[i].seq;
        }
      }
      write_event(log, eventnum, utime + 20, "HX_COMMAND", encoded(command));
    }
  }
  return rec;
}

class IdentifySeries : public ::testing::Test {
 protected:
  std::string path(const std::string& name) const { return scratch_.path(name); }
  testing::ScratchDir scratch_{"hystloop_identify_series"};
  const std::vector<ctl::SeriesStep> steps_ = ctl::banning_series(short_plan());
  const double seconds_ = ctl::series_duration_s(steps_) + 0.2;
};

TEST_F(IdentifySeries, EveryExperimentIsFoundAtTheTicksTheCompensatorRanIt) {
  const Recording rec = record_series(path("run.lcmlog"), steps_, {}, seconds_);
  const LoggedExperiments logged = read_logged_experiments({path("run.lcmlog")}, {});
  ASSERT_EQ(logged.experiments.size(), steps_.size()) << describe(logged);
  EXPECT_EQ(logged.requests, steps_.size());
  EXPECT_EQ(logged.blocks, 1u);
  EXPECT_TRUE(logged.notes.empty()) << describe(logged);
  const auto ticks = experiment_schedule(rec.first_experiment_tick, rec.specs, 1e-4);
  double start_s = static_cast<double>(rec.first_experiment_tick) * 1e-4;
  for (std::size_t i = 0; i < steps_.size(); ++i) {
    const LoggedExperiment& e = logged.experiments[i];
    EXPECT_EQ(e.request_id, 7000 + static_cast<std::int64_t>(i));
    EXPECT_EQ(e.begin_tick, ticks[i].begin);
    EXPECT_EQ(e.end_tick, ticks[i].end);
    EXPECT_EQ(e.spec.settle, steps_[i].request.kind == "settle");
    EXPECT_TRUE(e.usable()) << i << ": " << e.problem;
    EXPECT_TRUE(e.complete);
    ASSERT_EQ(e.samples.u.size(), static_cast<std::size_t>(e.end_tick - e.begin_tick));
    // The requested sine, its phase continuing from where the previous experiment ended, after
    // the approach from the previous offset at the conservative ramp (compensator.
    // experiment_ramp_V_per_s, 1000 V/s: 0.1 V a tick, far below the slew limit's 5 V).
    double worst = 0.0;
    std::size_t ramp = 0;
    bool met = false;
    for (std::size_t k = 0; k < e.samples.u.size(); ++k) {
      const double t = static_cast<double>(e.begin_tick + static_cast<std::int64_t>(k)) * 1e-4 - start_s;
      const double expected =
          e.spec.offset_V + e.spec.amplitude_V * std::sin(2.0 * std::numbers::pi * e.spec.frequency_hz * t);
      met = met || std::abs(e.samples.u[k] - expected) <= 1e-9;
      if (!met) {
        ++ramp;
        if (k > 0) {
          EXPECT_LE(std::abs(e.samples.u[k] - e.samples.u[k - 1]), 0.1 + 1e-9) << i;
        }
        continue;
      }
      worst = std::max(worst, std::abs(e.samples.u[k] - expected));
    }
    EXPECT_LT(worst, 1e-9) << i;
    // The largest jump of this plan is 120 V: 1,200 ticks at most (fewer where the sine comes to
    // meet the ramp); a measurement follows its settling at the same offset: no approach.
    EXPECT_LE(ramp, 1200u) << i;
    if (!e.spec.settle) {
      EXPECT_EQ(ramp, 0u) << i;
    }
    start_s = experiment_end_s(start_s, e.spec);
  }
  // Back to back: no tick between two experiments.
  for (std::size_t i = 1; i < logged.experiments.size(); ++i) {
    EXPECT_EQ(logged.experiments[i].begin_tick, logged.experiments[i - 1].end_tick);
  }
}

TEST_F(IdentifySeries, AStoppedSeriesCutsItsExperimentShortAndDropsTheQueue) {
  Faults f;
  f.stop_at_tick = kRequestTick + 10'500;  // 1.05 s in: inside the second offset experiment's settling
  record_series(path("run.lcmlog"), steps_, f, seconds_);
  const LoggedExperiments logged = read_logged_experiments({path("run.lcmlog")}, {});
  ASSERT_FALSE(logged.experiments.empty());
  const LoggedExperiment& last = logged.experiments.back();
  EXPECT_FALSE(last.complete);
  EXPECT_NE(last.problem.find("cut short"), std::string::npos) << last.problem;
  for (std::size_t i = 0; i + 1 < logged.experiments.size(); ++i) EXPECT_TRUE(logged.experiments[i].usable());
  const std::size_t dropped = steps_.size() - logged.experiments.size();
  EXPECT_GT(dropped, 0u);
  std::size_t never_ran = 0;
  for (const auto& n : logged.notes) never_ran += n.find("never ran") != std::string::npos ? 1 : 0;
  EXPECT_EQ(never_ran, dropped) << describe(logged);
}

TEST_F(IdentifySeries, ARequestMissingFromTheLogIsFoundByTheCommandsNotMislabelled) {
  Faults f;
  f.requests_not_logged = {4};  // the third experiment's settling
  record_series(path("run.lcmlog"), steps_, f, seconds_);
  const LoggedExperiments logged = read_logged_experiments({path("run.lcmlog")}, {});
  ASSERT_GE(logged.experiments.size(), 5u) << describe(logged);
  for (std::size_t i = 0; i < 4; ++i) EXPECT_TRUE(logged.experiments[i].usable()) << i;
  for (std::size_t i = 4; i < logged.experiments.size(); ++i) {
    EXPECT_NE(logged.experiments[i].problem.find("a request is missing from the log"), std::string::npos)
        << i << ": " << logged.experiments[i].problem;
  }
}

TEST_F(IdentifySeries, MissingSamplesSpoilAFrequencyExperimentButNotALoop) {
  // Find the experiments' ticks from a clean recording first.
  const Recording rec = record_series(path("clean.lcmlog"), steps_, {}, seconds_);
  const auto schedule = experiment_schedule(rec.first_experiment_tick, rec.specs, 1e-4);
  const std::size_t loop = 1;                  // offset -60 V, measured at 5 Hz: 4000 ticks
  const std::size_t fast = steps_.size() - 1;  // 2400 Hz, measured
  Faults loop_gap;
  loop_gap.drop_samples_from = schedule[loop].begin + 1000;
  loop_gap.drop_samples_count = 5;
  record_series(path("loop.lcmlog"), steps_, loop_gap, seconds_);
  LoggedExperiments logged = read_logged_experiments({path("loop.lcmlog")}, {});
  ASSERT_EQ(logged.experiments.size(), steps_.size());
  EXPECT_TRUE(logged.experiments[loop].usable()) << logged.experiments[loop].problem;
  EXPECT_EQ(logged.experiments[loop].missing, 5u);
  ExperimentLogOptions strict;
  strict.max_missing = 0.0;
  logged = read_logged_experiments({path("loop.lcmlog")}, strict);
  EXPECT_FALSE(logged.experiments[loop].usable());

  Faults fast_gap;
  fast_gap.drop_samples_from = schedule[fast].begin + 100;
  fast_gap.drop_samples_count = 1;
  record_series(path("fast.lcmlog"), steps_, fast_gap, seconds_);
  logged = read_logged_experiments({path("fast.lcmlog")}, {});
  EXPECT_FALSE(logged.experiments[fast].usable());
  EXPECT_NE(logged.experiments[fast].problem.find("time base"), std::string::npos) << logged.experiments[fast].problem;
}

// A loop is a function of the voltage applied, which the samples record: late (held) commands
// do not spoil it. A frequency-response experiment's input spectrum they do.
TEST_F(IdentifySeries, LateCommandsSpoilAFrequencyExperimentButNotALoop) {
  const Recording rec = record_series(path("clean.lcmlog"), steps_, {}, seconds_);
  const auto schedule = experiment_schedule(rec.first_experiment_tick, rec.specs, 1e-4);
  const std::size_t loop = 1, fast = steps_.size() - 1;
  Faults f;
  f.late_from = schedule[loop].begin + 100;
  f.late_count = 400;  // 10 % of the loop
  record_series(path("loop.lcmlog"), steps_, f, seconds_);
  LoggedExperiments logged = read_logged_experiments({path("loop.lcmlog")}, {});
  EXPECT_TRUE(logged.experiments[loop].usable()) << logged.experiments[loop].problem;
  EXPECT_EQ(logged.experiments[loop].not_as_commanded, 400u);
  f.late_from = schedule[fast].begin + 100;
  f.late_count = 30;  // 3 % of the 1000 ticks
  record_series(path("fast.lcmlog"), steps_, f, seconds_);
  logged = read_logged_experiments({path("fast.lcmlog")}, {});
  EXPECT_FALSE(logged.experiments[fast].usable());
  EXPECT_NE(logged.experiments[fast].problem.find("not applied as commanded"), std::string::npos);
  ExperimentLogOptions lenient;
  lenient.max_not_as_commanded = 0.05;
  logged = read_logged_experiments({path("fast.lcmlog")}, lenient);
  EXPECT_TRUE(logged.experiments[fast].usable()) << logged.experiments[fast].problem;
}

TEST_F(IdentifySeries, NoExperimentInTheLogIsAClearError) {
  record_series(path("run.lcmlog"), {}, {}, 0.1);
  try {
    read_logged_experiments({path("run.lcmlog")}, {});
    FAIL();
  } catch (const SampleLogError& e) {
    EXPECT_NE(std::string(e.what()).find("no experiment ran"), std::string::npos) << e.what();
  }
}

// The tool, as a user runs it on the logger's file: Banning's a, b, alpha, k, c come back.
TEST_F(IdentifySeries, ToolFitsTheStageFromTheLog) {
  record_series(path("run.lcmlog"), steps_, {}, seconds_);
  const auto r = testing::run_tool(std::string(HYSTLOOP_IDENTIFY_EXE) + " --model banning " + path("run.lcmlog") +
                                   " --out " + path("b.yaml"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find(std::to_string(steps_.size()) + " experiment(s) ran (" + std::to_string(steps_.size() / 2) +
                          " measured, " + std::to_string(steps_.size() / 2) + " usable)"),
            std::string::npos)
      << r.output;
  const YAML::Node b = YAML::LoadFile(path("b.yaml"))["banning"];
  const BanningStageParams truth{};
  EXPECT_NEAR(b["hysteresis"]["a"].as<double>(), truth.hysteresis.a, 0.005 * truth.hysteresis.a) << r.output;
  EXPECT_NEAR(b["hysteresis"]["b"].as<double>(), truth.hysteresis.b, 0.01 * truth.hysteresis.b) << r.output;
  EXPECT_NEAR(b["hysteresis"]["alpha"].as<double>(), truth.hysteresis.alpha, 0.05 * truth.hysteresis.alpha) << r.output;
  EXPECT_NEAR(b["stage"]["k"].as<double>(), truth.stage.k, 0.02 * truth.stage.k) << r.output;
  EXPECT_NEAR(b["stage"]["c"].as<double>(), truth.stage.c, 0.05 * truth.stage.c) << r.output;
}

// --experiment N: any model on one experiment the loop ran, as listed.
TEST_F(IdentifySeries, ToolFitsOneListedExperimentWithAnyModel) {
  const Recording rec = record_series(path("run.lcmlog"), steps_, {}, seconds_);
  const auto schedule = experiment_schedule(rec.first_experiment_tick, rec.specs, 1e-4);
  const std::string tool = std::string(HYSTLOOP_IDENTIFY_EXE) + " " + path("run.lcmlog");
  // Experiment 3 is the +60 V offset loop (2 periods at 5 Hz, 4000 ticks give or take the
  // schedule's rounding): a line through it passes through the loop's centre, which lies on
  // y = a u (Banning, Theorem 3).
  const std::int64_t ticks = schedule[3].end - schedule[3].begin;
  EXPECT_NEAR(static_cast<double>(ticks), 4000.0, 1.0);
  auto r = testing::run_tool(tool + " --model linear --experiment 3");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("fitting experiment 3: " + std::to_string(ticks) + " samples"), std::string::npos)
      << r.output;
  double gain = 0.0, offset = 0.0;
  ASSERT_EQ(std::sscanf(r.output.substr(r.output.find("linear: gain ")).c_str(), "linear: gain %lf m/V, offset %lf m",
                        &gain, &offset),
            2)
      << r.output;
  const double a = BanningStageParams{}.hysteresis.a;
  EXPECT_NEAR(offset + gain * 60.0, a * 60.0, 0.005 * a * 60.0) << r.output;
  r = testing::run_tool(tool + " --model mem --experiment 99");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("the log holds " + std::to_string(steps_.size()) + " experiment(s)"), std::string::npos)
      << r.output;
  r = testing::run_tool(tool + " --model mem --experiment 1 --from 1");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("not with --from/--to"), std::string::npos) << r.output;
}

// A log with one experiment fitted whole (the demo's: the identification experiment, then
// tracking) is fitted as asked, with a note that lists the experiment and names --experiment.
TEST_F(IdentifySeries, OneExperimentInAWholeLogFitIsNotedWithHowToFitItAlone) {
  std::vector<ctl::SeriesStep> one(1);
  one[0].request = {"sine", 250.0, 10.0, 1.0, 0.0};
  record_series(path("one.lcmlog"), one, {}, 1.6);
  const std::string tool = std::string(HYSTLOOP_IDENTIFY_EXE) + " " + path("one.lcmlog");
  auto r = testing::run_tool(tool + " --model linear");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("the log holds 1 experiment(s) the loop ran; fit one alone with --experiment N"),
            std::string::npos)
      << r.output;
  EXPECT_TRUE(std::regex_search(r.output, std::regex("\\n +0  sine +0 +250 +10 +1 "))) << r.output;
  r = testing::run_tool(tool + " --model linear --experiment 0");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(r.output.find("note: this fit is over the whole record"), std::string::npos) << r.output;
}

// A log with two experiments and none chosen: a fit over both would mix two loops into a model
// that fits neither, so the tool lists them (index, kind, amplitude, frequency, duration, time
// range) and names --experiment, exit 2; the first of them then fits as --experiment 0.
TEST_F(IdentifySeries, TwoExperimentsAreListedAndNoneIsFittedUntilOneIsChosen) {
  std::vector<ctl::SeriesStep> two(2);
  two[0].request = {"sine", 250.0, 10.0, 1.0, 0.0};  // the MEM paper's input, 1 s
  two[1].request = {"sine", 100.0, 5.0, 0.4, 50.0};
  const Recording rec = record_series(path("two.lcmlog"), two, {}, 1.6);
  // t as --from/--to count it: from the record's first sample; experiment 1 follows 0 at once.
  const double t0 = static_cast<double>(rec.first_experiment_tick - kFirstSeq) * 1e-4;
  char t[4][16];
  for (int i = 0; i < 4; ++i) std::snprintf(t[i], sizeof t[i], "%.4f", t0 + std::array{0.0, 1.0, 1.0, 1.4}[i]);
  const std::string tool = std::string(HYSTLOOP_IDENTIFY_EXE) + " " + path("two.lcmlog");
  for (const char* model : {"mem", "auto"}) {
    const auto r = testing::run_tool(tool + " --model " + model + " --out " + path("never.yaml"));
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_NE(r.output.find("holds 2 experiments the loop ran; fit one with --experiment N"), std::string::npos)
        << r.output;
    // Both listed with their figures: index, kind, offset, amplitude, frequency, duration, time range.
    const std::regex row0("\\n +0  sine +0 +250 +10 +1 +" + std::string(t[0]) + " \\.\\. " + t[1] + " +usable");
    const std::regex row1("\\n +1  sine +50 +100 +5 +0\\.4 +" + std::string(t[2]) + " \\.\\. " + t[3] + " +usable");
    EXPECT_TRUE(std::regex_search(r.output, row0)) << r.output;
    EXPECT_TRUE(std::regex_search(r.output, row1)) << r.output;
    EXPECT_EQ(r.output.find("c3 ="), std::string::npos) << "fitted although none was chosen: " << r.output;
    EXPECT_FALSE(std::filesystem::exists(path("never.yaml")));
  }
  const auto one = testing::run_tool(tool + " --model mem --experiment 0");
  EXPECT_EQ(one.exit_code, 0) << one.output;
  EXPECT_NE(one.output.find("fitting experiment 0: 10000 samples"), std::string::npos) << one.output;
  // A time range is a choice too: the record as it is, between the times given.
  const auto range = testing::run_tool(tool + " --model linear --from " + t[2] + " --to " + t[3]);
  EXPECT_EQ(range.exit_code, 0) << range.output;
}

// hystloop-ctl experiment --kind multisine --band 10:2800 --amplitude 0.8 --offset 20 --period 0.1
// --periods 3 --realisations 2, run by the compensator on the simulated Banning stage and logged;
// hystloop-identify --model stage finds it in the log (its layout from the request) and recovers
// the stage's resonance (Banning et al. Table 2: 1.72 kHz, damping 0.094) through the hysteresis's
// small-signal gain, which it reports beside the unit-DC-gain stage.
TEST_F(IdentifySeries, TheStageFromTheLoopsMultisineExperiment) {
  ctl::SeriesStep step;
  step.request.kind = "multisine";
  ctl::parse_band("10:2800", step.request);
  step.request.amplitude_V = 0.8;
  step.request.offset_V = 20.0;
  step.request.duration_s = 0.1;
  step.request.multisine.periods = 3;
  step.request.multisine.realisations = 2;
  const std::string log = path("multisine.lcmlog");
  const Recording rec = record_series(log, {step}, {}, 1.2);
  ASSERT_GE(rec.first_experiment_tick, 0);
  const auto r =
      testing::run_tool(std::string(HYSTLOOP_IDENTIFY_EXE) + " " + log + " --model stage --out " + path("stage.yaml"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("measured DC gain"), std::string::npos) << r.output;
  const YAML::Node doc = YAML::LoadFile(path("stage.yaml"));
  const YAML::Node poles = doc["stage"]["poles_hz"];
  ASSERT_GE(poles.size(), 1u) << r.output;
  const double k = SecondOrderStageParams{}.k, c = SecondOrderStageParams{}.c;
  const std::complex<double> truth(-c / 2.0 / (2.0 * std::numbers::pi),
                                   std::sqrt(k - c * c / 4.0) / (2.0 * std::numbers::pi));
  double nearest = 1e300;
  for (const auto& p : poles) {
    nearest = std::min(nearest, std::abs(std::complex<double>(p[0].as<double>(), p[1].as<double>()) - truth));
  }
  EXPECT_LT(nearest / std::abs(truth), 0.02) << r.output;
}

}  // namespace
}  // namespace hystloop
