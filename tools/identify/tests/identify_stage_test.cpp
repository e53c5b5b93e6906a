// hystloop-identify --model stage end to end: a CSV made here from a known two-mode stage with a
// delay of 1.5 ticks (LinearStageSimulator, the rig's convention: y_k at the end of tick k), driven
// by design_multisine's record, times an actuator gain, plus sensor noise; the tool run as a
// process; its YAML's poles and delay against the true ones, and the Bode plots.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <complex>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "loop/servo_notches.hpp"
#include "models/linear_stage.hpp"
#include "models/multisine.hpp"
#include "support/tool_run.hpp"

namespace hystloop {
namespace {

const std::string kTool = HYSTLOOP_IDENTIFY_EXE;
using C = std::complex<double>;

constexpr double kGain_m_per_V = 2e-7;
constexpr double kDelay_s = 150e-6;

LinearStageSpec truth() { return LinearStageSpec::sum_of_modes({{780.0, 0.03, 0.8}, {2400.0, 0.02, 0.2}}, kDelay_s); }

// The true poles in Hz, conjugate pairs once: -zeta f + i f sqrt(1 - zeta^2).
std::vector<C> true_poles_hz() {
  std::vector<C> p;
  for (auto [f, z] : {std::pair{780.0, 0.03}, std::pair{2400.0, 0.02}})
    p.emplace_back(-z * f, f * std::sqrt(1 - z * z));
  return p;
}

class IdentifyStage : public ::testing::Test {
 protected:
  std::string path(const std::string& name) const { return scratch_.path(name); }
  testing::ScratchDir scratch_{"hystloop_identify_stage"};

  // 300 samples at rest before the record (--skip), then R P N samples.
  void write_record(const std::string& file, bool with_t) {
    MultisineOptions o;
    o.period_samples = 2000;
    o.f_min_Hz = 5.0;
    o.f_max_Hz = 3000.0;
    o.amplitude_V = 2.0;
    o.offset_V = 10.0;
    o.periods = 4;
    o.realisations = 3;
    o.seed = 11;
    const Multisine m = design_multisine(o);
    std::vector<double> u(300, o.offset_V);
    u.insert(u.end(), m.u_V.begin(), m.u_V.end());
    LinearStageSimulator sim(discretise(truth(), 1e-4));
    sim.reset(o.offset_V);
    std::mt19937_64 rng(3);
    std::normal_distribution<double> noise(0.0, 1e-10);
    std::FILE* f = std::fopen(file.c_str(), "w");
    ASSERT_NE(f, nullptr);
    std::fprintf(f, with_t ? "t,u,y\n" : "u,y\n");
    for (std::size_t k = 0; k < u.size(); ++k) {
      const double y = kGain_m_per_V * sim.step(u[k]) + noise(rng);
      if (with_t) std::fprintf(f, "%.9g,", static_cast<double>(k) * 1e-4);
      std::fprintf(f, "%.17g,%.17g\n", u[k], y);
    }
    std::fclose(f);
  }
};

std::vector<C> roots(const YAML::Node& list) {
  std::vector<C> out;
  for (const auto& r : list) out.emplace_back(r[0].as<double>(), r[1].as<double>());
  return out;
}

TEST_F(IdentifyStage, RecoversTheTwoModeStageAndItsDelayFromACsv) {
  write_record(path("stage.csv"), true);
  const std::string out = path("fit") + "/";
  const testing::ToolRun r = testing::run_tool(kTool + " " + path("stage.csv") +
                                               " --model stage --period-samples 2000 --periods 4 --realisations 3 "
                                               "--skip 300 --max-order 5 --out " +
                                               out);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("chi2/line"), std::string::npos) << r.output;  // the orders tried
  EXPECT_NE(r.output.find("measured DC gain"), std::string::npos) << r.output;
  const YAML::Node doc = YAML::LoadFile(out + "config.yaml");
  const std::vector<C> poles = roots(doc["stage"]["poles_hz"]);
  ASSERT_EQ(poles.size(), 2u) << r.output;  // two conjugate pairs, listed once
  for (const C t : true_poles_hz()) {
    const C nearest =
        *std::min_element(poles.begin(), poles.end(), [&](C a, C b) { return std::abs(a - t) < std::abs(b - t); });
    EXPECT_LT(std::abs(nearest - t) / std::abs(t), 1e-3) << nearest << " vs " << t;
  }
  EXPECT_EQ(doc["stage"]["kind"].as<std::string>(), "linear");  // the compensator's stage section as it is
  EXPECT_EQ(doc["stage"]["zeros_hz"].size(), 1u);               // the pair two modes in parallel have
  EXPECT_NEAR(doc["stage"]["delay_s"].as<double>(), kDelay_s, 0.5e-6);
  // How far up the model is known: above the lowest mode, below the anti-resonance (learning_for_stage
  // then learns to 0.7 of it).
  const double known_to_hz = doc["stage"]["known_to_hz"].as<double>();
  EXPECT_GT(known_to_hz, 780.0) << r.output;
  EXPECT_LE(known_to_hz, 3000.0) << r.output;
  // The gain is reported beside the stage, not in it.
  const std::string gain_label = "measured DC gain u -> y: ";
  const std::size_t at = r.output.find(gain_label);
  ASSERT_NE(at, std::string::npos) << r.output;
  EXPECT_NEAR(std::stod(r.output.substr(at + gain_label.size())), kGain_m_per_V, 1e-4 * kGain_m_per_V);
  // The fitted order: the stage's 2/4, the lower ones refused by their chi-square.
  EXPECT_NE(r.output.find("stage model: orders 2/4,"), std::string::npos) << r.output;
  for (const char* png : {"stage_bode.png", "stage_residual.png"}) {
    EXPECT_TRUE(std::filesystem::exists(out + png)) << png << "\n" << r.output;
  }
  EXPECT_TRUE(std::filesystem::exists(out + "stage_frf.dat"));
  // The servo's notches, from the identified model: those the true stage gives, to the fit's accuracy.
  const std::vector<ModeNotch> want = notches_for_stage(truth(), 1e4);
  ASSERT_EQ(want.size(), 2u);
  for (std::size_t i = 0; i < want.size(); ++i) {
    const std::string label = "servo notch " + std::to_string(i + 1) + ": ";
    const std::size_t n = r.output.find(label);
    ASSERT_NE(n, std::string::npos) << r.output;
    double hz = 0.0, q = 0.0;
    ASSERT_EQ(std::sscanf(r.output.c_str() + n + label.size(), "%lf Hz, Q %lf", &hz, &q), 2) << r.output;
    EXPECT_NEAR(hz, want[i].notch.hz, 1e-3 * want[i].notch.hz) << i;
    EXPECT_NEAR(q, want[i].notch.q, 0.02 * want[i].notch.q) << i;
  }
  // The servo's integral gain, designed on the identified model: the true stage's to the fit's accuracy.
  const double want_ki = servo_for_stage(truth(), FeedbackGains{}).gains.ki;
  const std::size_t g = r.output.find("servo gains: kp 0, ki ");
  ASSERT_NE(g, std::string::npos) << r.output;
  double ki = 0.0;
  ASSERT_EQ(std::sscanf(r.output.c_str() + g + 22, "%lf", &ki), 1) << r.output;
  EXPECT_NEAR(ki, want_ki, 0.05 * want_ki);
  EXPECT_NE(r.output.find("hystloop-ctl gains --kp 0 --ki "), std::string::npos) << r.output;
  std::ifstream yaml(out + "config.yaml");
  std::stringstream text;
  text << yaml.rdbuf();
  EXPECT_NE(text.str().find("#   notch2_hz: "), std::string::npos) << text.str();
  EXPECT_NE(text.str().find("#   kp: 0   ki: "), std::string::npos) << text.str();
}

// A simulated record held against the stage it came from: the model's error in dB and degrees,
// and the true response inside the measured band (what tells a lab the fit is as good as the data).
TEST_F(IdentifyStage, ASimulatedRecordIsHeldAgainstItsTrueStage) {
  write_record(path("stage.csv"), true);
  {
    std::ofstream y(path("bridge.yaml"));
    y << "plant:\n  stage:\n    modes:\n      - {frequency_hz: 780.0, damping_ratio: 0.03, weight: 0.8}\n"
         "      - {frequency_hz: 2400.0, damping_ratio: 0.02, weight: 0.2}\n    delay_s: 150.0e-6\n";
  }
  const std::string cmd = kTool + " " + path("stage.csv") +
                          " --model stage --period-samples 2000 --periods 4 --realisations 3 --skip 300 --max-order 5 "
                          "--out " +
                          path("fit.yaml");
  const testing::ToolRun r = testing::run_tool(cmd + " --true-stage " + path("bridge.yaml"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string label = "against the true stage (plant.stage of " + path("bridge.yaml") + "), up to 3000 Hz: ";
  const std::size_t at = r.output.find(label);
  ASSERT_NE(at, std::string::npos) << r.output;
  double dB = 1e9, f1 = 0, deg = 1e9, f2 = 0;
  std::size_t inside = 0, lines = 0;
  ASSERT_EQ(std::sscanf(r.output.c_str() + at + label.size(),
                        "model within %lf dB (worst at %lf Hz) and %lf deg (at %lf Hz); the true response inside "
                        "the measured +-2 sigma band at %zu of %zu lines",
                        &dB, &f1, &deg, &f2, &inside, &lines),
            6)
      << r.output;
  EXPECT_LT(dB, 0.5);
  EXPECT_LT(deg, 3.0);
  EXPECT_GT(lines, 100U);
  // +-2 sigma would hold 95 % of the lines with sigma known; estimated from 3 realisations (4 degrees
  // of freedom) it holds ~88 % (Student's t): 536 of 599 here.
  EXPECT_GE(inside, lines * 8 / 10);
  // A wrong "truth" is seen as such: the dominant mode 10 % off.
  {
    std::ofstream y(path("wrong.yaml"));
    y << "stage:\n  modes:\n    - {frequency_hz: 858.0, damping_ratio: 0.03, weight: 0.8}\n"
         "    - {frequency_hz: 2400.0, damping_ratio: 0.02, weight: 0.2}\n  delay_s: 150.0e-6\n";
  }
  const testing::ToolRun wrong = testing::run_tool(cmd + " --true-stage " + path("wrong.yaml"));
  ASSERT_EQ(wrong.exit_code, 0) << wrong.output;
  const std::size_t w = wrong.output.find("model within ");
  ASSERT_NE(w, std::string::npos) << wrong.output;
  EXPECT_GT(std::stod(wrong.output.substr(w + 13)), 3.0) << wrong.output;
  // A file without a stage is refused.
  {
    std::ofstream y(path("none.yaml"));
    y << "bridge: {rate_hz: 10000}\n";
  }
  EXPECT_EQ(testing::run_tool(cmd + " --true-stage " + path("none.yaml")).exit_code, 2);
}

TEST_F(IdentifyStage, AUyCsvNeedsItsSampleRateAndAGivenOrderIsKept) {
  write_record(path("uy.csv"), false);
  const std::string layout = " --model stage --period-samples 2000 --periods 4 --realisations 3 --skip 300";
  const testing::ToolRun no_rate = testing::run_tool(kTool + " " + path("uy.csv") + layout);
  EXPECT_EQ(no_rate.exit_code, 2) << no_rate.output;
  EXPECT_NE(no_rate.output.find("--sample-rate"), std::string::npos) << no_rate.output;
  const testing::ToolRun r =
      testing::run_tool(kTool + " " + path("uy.csv") + layout +
                        " --sample-rate 10000 --order 2/4 --band 5:3000 --out " + path("stage.yaml"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const YAML::Node doc = YAML::LoadFile(path("stage.yaml"));
  EXPECT_EQ(doc["stage"]["poles_hz"].size(), 2u);
  EXPECT_NEAR(doc["stage"]["delay_s"].as<double>(), kDelay_s, 0.5e-6);
  // How far up the model is known: above the lowest mode, below the anti-resonance (learning_for_stage
  // then learns to 0.7 of it).
  const double known_to_hz = doc["stage"]["known_to_hz"].as<double>();
  EXPECT_GT(known_to_hz, 780.0) << r.output;
  EXPECT_LE(known_to_hz, 3000.0) << r.output;
  const testing::ToolRun bad =
      testing::run_tool(kTool + " " + path("uy.csv") + layout + " --sample-rate 1e4 --order 4/2");
  EXPECT_EQ(bad.exit_code, 2) << bad.output;
  EXPECT_NE(bad.output.find("order"), std::string::npos) << bad.output;
}

}  // namespace
}  // namespace hystloop
