// hystloop-identify end to end on CSV input: CSVs generated here, the tool run as a process, its
// printed and written parameters checked; a malformed file and an unfit record give their reasons.
// (All of hystloop-identify's tests live in tools/identify/tests/: logs, series, publishing, CSV.)
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <string>
#include <string_view>
#include <vector>

#include "core/errors.hpp"
#include "ident/banning_experiments.hpp"
#include "ident/mem_test_data.hpp"
#include "models/model_set.hpp"
#include "sample_budget.hpp"
#include "support/tool_run.hpp"

namespace hystloop {
namespace {

const std::string kTool = HYSTLOOP_IDENTIFY_EXE;

using testing::ToolRun;

ToolRun run_tool(const std::string& args) { return testing::run_tool(kTool + " " + args); }

class IdentifyTool : public ::testing::Test {
 protected:
  std::string path(const std::string& name) const { return scratch_.path(name); }
  testing::ScratchDir scratch_{"hystloop_identify"};
};

void write_csv(const std::string& file, const std::vector<double>& u, const std::vector<double>& y, double fs) {
  std::FILE* f = std::fopen(file.c_str(), "w");
  ASSERT_NE(f, nullptr);
  std::fprintf(f, "t,u,y\n");
  for (std::size_t k = 0; k < u.size(); ++k)
    std::fprintf(f, "%.9g,%.17g,%.17g\n", static_cast<double>(k) / fs, u[k], y[k]);
  std::fclose(f);
}

TEST_F(IdentifyTool, FitsMemAndWritesTheYamlSnippet) {
  const MemParams truth = MemParams::paper_like();
  const auto u = testdata::paper_identification_input();
  std::vector<double> y = testdata::model_output(truth, u);
  testdata::add_noise(y, 1e-9, 5);
  write_csv(path("mem.csv"), u, y, 1e4);
  const ToolRun r = run_tool(path("mem.csv") + " --model mem --out " + path("params.yaml"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("mem: c1 "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("residual"), std::string::npos) << r.output;
  const YAML::Node doc = YAML::LoadFile(path("params.yaml"));
  EXPECT_NEAR(doc["mem"]["c1"].as<double>(), truth.c1, 0.01 * truth.c1);
  EXPECT_NEAR(doc["mem"]["c2"].as<double>(), truth.c2, 0.02 * truth.c2);
  EXPECT_NEAR(doc["mem"]["c3"].as<double>(), truth.c3, 0.01 * truth.c3);

  // The paper's derivative form through the CLI too.
  const ToolRun d = run_tool(path("mem.csv") + " --model mem --form derivative");
  EXPECT_EQ(d.exit_code, 0) << d.output;
  EXPECT_NE(d.output.find("derivative form"), std::string::npos) << d.output;

  // auto ranks every model; MEM wins on MEM data.
  const ToolRun a = run_tool(path("mem.csv") + " --model auto --out " + path("auto.yaml"));
  ASSERT_EQ(a.exit_code, 0) << a.output;
  EXPECT_NE(a.output.find("best: mem"), std::string::npos) << a.output;
  EXPECT_TRUE(YAML::LoadFile(path("auto.yaml"))["mem"]);
}

TEST_F(IdentifyTool, MalformedFileNamesLineAndColumn) {
  {
    std::ofstream f(path("bad.csv"));
    f << "t,u,y\n0,0,0\n0.0001,1.5,abc\n";
  }
  const ToolRun r = run_tool(path("bad.csv") + " --model mem");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("bad.csv:3"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("column 'y'"), std::string::npos) << r.output;
  {
    std::ofstream f(path("nohdr.csv"));
    f << "time,volts\n0,0\n";
  }
  const ToolRun h = run_tool(path("nohdr.csv") + " --model mem");
  EXPECT_EQ(h.exit_code, 2) << h.output;
  EXPECT_NE(h.output.find("lacks column"), std::string::npos) << h.output;
}

TEST_F(IdentifyTool, UnfitRecordExitsNonZeroWithTheReason) {
  const std::vector<double> u(2000, 5.0), y(2000, 1e-9);
  write_csv(path("flat.csv"), u, y, 1e4);
  const ToolRun r = run_tool(path("flat.csv") + " --model mem");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("constant_input"), std::string::npos) << r.output;
}

TEST_F(IdentifyTool, BanningFromOneFileWithAnExperimentColumn) {
  BanningPlanOptions plan_options;
  plan_options.offsets_V = {-80.0, 0.0, 80.0};
  plan_options.small_amplitudes_V = {1.0, 3.0};
  plan_options.amplitudes_V = {50.0, 100.0, 200.0};
#if defined(__SANITIZE_ADDRESS__)
  plan_options.hysteresis_frequency_Hz = 5.0;  // lighter under the sanitizer (the fit corrects the lag)
  plan_options.settle_periods = 10;
#else
  plan_options.hysteresis_frequency_Hz = 2.0;
#endif
  plan_options.frequencies_Hz = {100.0, 800.0, 1400.0, 1650.0, 1720.0, 1800.0, 2100.0, 2800.0};
  const BanningStageParams truth{};
  const auto plan = plan_banning_experiments(plan_options);
  {
    std::FILE* f = std::fopen(path("banning.csv").c_str(), "w");
    ASSERT_NE(f, nullptr);
    std::fprintf(f, "experiment,t,u,y\n");
    for (std::size_t i = 0; i < plan.size(); ++i) {
      const auto y = run_on_stage(truth, plan[i], 1e-9, 100 + i);
      for (std::size_t k = plan[i].measure_begin; k < plan[i].u.size(); ++k) {
        std::fprintf(f, "e%zu,%.9g,%.17g,%.17g\n", i, static_cast<double>(k) * 1e-4, plan[i].u[k], y[k]);
      }
    }
    std::fclose(f);
  }
  const ToolRun r = run_tool(path("banning.csv") + " --model banning --out " + path("banning.yaml"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("alpha = "), std::string::npos) << r.output;
  const YAML::Node doc = YAML::LoadFile(path("banning.yaml"));
  EXPECT_NEAR(doc["banning"]["hysteresis"]["a"].as<double>(), truth.hysteresis.a, 0.005 * truth.hysteresis.a);
  EXPECT_NEAR(doc["banning"]["hysteresis"]["b"].as<double>(), truth.hysteresis.b, 0.01 * truth.hysteresis.b);
  EXPECT_NEAR(doc["banning"]["hysteresis"]["alpha"].as<double>(), truth.hysteresis.alpha,
              0.04 * truth.hysteresis.alpha);
  EXPECT_NEAR(doc["banning"]["stage"]["k"].as<double>(), truth.stage.k, 0.01 * truth.stage.k);
  EXPECT_NEAR(doc["banning"]["stage"]["c"].as<double>(), truth.stage.c, 0.05 * truth.stage.c);
}

// The probe's fits that were not fits: a record scaled by 1e300 gave "residual -nan" (mem) and
// k1 = 5.4e301 (katalenic), both with exit 0. Refused by the reader, naming line and column.
TEST_F(IdentifyTool, DataBeyondPhysicalSanityIsRefusedNamingLineAndColumn) {
  auto u = testdata::paper_identification_input();
  u.resize(4000);
  MemModel model(MemParams::paper_like());
  model.reset(0.0);
  std::vector<double> y(u.size());
  for (std::size_t k = 0; k < u.size(); ++k) y[k] = model.forward(u[k]) * 1e300, u[k] *= 1e300;
  write_csv(path("huge.csv"), u, y, 1e4);
  for (const char* m : {"mem", "katalenic", "auto"}) {
    const ToolRun r = run_tool(path("huge.csv") + " --model " + m);
    EXPECT_EQ(r.exit_code, 2) << m << ": " << r.output;
    EXPECT_EQ(r.output.find("nan"), std::string::npos) << m << ": " << r.output;
    EXPECT_NE(r.output.find("huge.csv:3: column 'u': "), std::string::npos) << m << ": " << r.output;
    EXPECT_NE(r.output.find("sanity bound"), std::string::npos) << m << ": " << r.output;
  }
}

TEST_F(IdentifyTool, AFolderInsteadOfAFileIsAUsageError) {
  const ToolRun r = run_tool(scratch_.path("") + " --model mem");
  EXPECT_EQ(r.exit_code, 2) << r.output;  // was CLI11's 105
  EXPECT_NE(r.output.find("directory"), std::string::npos) << r.output;
  EXPECT_EQ(run_tool("--model nope x.csv").exit_code, 2);
}

TEST_F(IdentifyTool, MoreSamplesThanTheBoundAreRefusedWithAHint) {
  const MemParams truth = MemParams::paper_like();
  const auto u = testdata::paper_identification_input();  // 20000 samples
  std::vector<double> y = testdata::model_output(truth, u);
  write_csv(path("mem.csv"), u, y, 1e4);
  const ToolRun r = run_tool(path("mem.csv") + " --model mem --max-samples 5000");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("20000 samples exceed --max-samples 5000"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("--decimate 4"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("mem: c1 "), std::string::npos) << r.output;  // refused before any fit
  // Decimated to the bound, the rate-independent MEM still fits.
  const ToolRun d =
      run_tool(path("mem.csv") + " --model mem --max-samples 5000 --decimate 4 --out " + path("params.yaml"));
  ASSERT_EQ(d.exit_code, 0) << d.output;
  EXPECT_NEAR(YAML::LoadFile(path("params.yaml"))["mem"]["c1"].as<double>(), truth.c1, 0.02 * truth.c1);
}

// --decimate K keeps every K-th sample and, for the rate-independent models, the input's turns
// between them: a 100 Hz line at 10 kHz with K = 10 has its peaks between kept samples. Every
// column keeps the same rows. Banning's fit reads sines at a uniform rate: plain stride there.
TEST(IdentifyDecimate, KeepsEveryKthSampleAndTheTurnsBetweenThem) {
  SampleTable full;
  for (int k = 0; k < 400; ++k) {
    full.t.push_back(k * 1e-4);
    full.u.push_back(100.0 * std::sin(2.0 * std::numbers::pi * 100.0 * k * 1e-4));  // peaks at k = 25, 75, ...
    full.y.push_back(full.u.back() * 1e-8);
    full.experiment.push_back(std::to_string(k));
  }
  const double peak = *std::max_element(full.u.begin(), full.u.end());
  SampleTable turns = full, plain = full;
  decimate(turns, 10, true);
  decimate(plain, 10, false);
  ASSERT_EQ(plain.u.size(), 40U);
  EXPECT_LT(*std::max_element(plain.u.begin(), plain.u.end()), peak - 1.0);  // the plain stride misses it
  EXPECT_DOUBLE_EQ(*std::max_element(turns.u.begin(), turns.u.end()), peak);
  EXPECT_GT(turns.u.size(), 40U);
  EXPECT_LT(turns.u.size(), 60U);  // two turns a period, four periods, and the last sample
  for (const SampleTable* d : {&turns, &plain}) {
    ASSERT_EQ(d->t.size(), d->u.size());
    ASSERT_EQ(d->y.size(), d->u.size());
    ASSERT_EQ(d->experiment.size(), d->u.size());
    for (std::size_t i = 0; i < d->u.size(); ++i) {
      const auto k = static_cast<std::size_t>(std::stoul(d->experiment[i]));
      EXPECT_EQ(d->u[i], full.u[k]);
      EXPECT_EQ(d->t[i], full.t[k]);
      EXPECT_EQ(d->y[i], full.y[k]);
    }
  }
}

TEST_F(IdentifyTool, ProgressOfALongFitOnStderr) {
  auto u = testdata::paper_identification_input();
  u.resize(6000);  // three periods
  write_csv(path("mem.csv"), u, testdata::model_output(MemParams::paper_like(), u), 1e4);
  // Katalenic simulates its operator per evaluation: ~30 ms here, 30 periods of the shortest
  // --progress-period-s (a 20 ms period once let a quick run finish before its first line).
  // Only stderr is collected: { tool 2>&1 >/dev/null; }.
  auto stderr_of = [&](const std::string& args) {
    return testing::run_tool("{ " + kTool + " " + path("mem.csv") + " " + args + " 2>&1 >/dev/null; }");
  };
  const ToolRun r = stderr_of("--model katalenic --progress --progress-period-s 0.001");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("hystloop-identify: fitting katalenic on 6000 samples: "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("fitting katalenic on 6000 samples: done in "), std::string::npos) << r.output;
  // Without the flag, and stderr not a terminal: quiet.
  const ToolRun q = stderr_of("--model katalenic");
  EXPECT_EQ(q.exit_code, 0) << q.output;
  EXPECT_EQ(q.output, "") << q.output;
}

TEST_F(IdentifyTool, HelpDescribesTheModels) {
  const ToolRun r = run_tool("--help");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("--model"), std::string::npos) << r.output;
  // --model's choices, from the model registry: every online model, then banning, stage and auto.
  std::vector<std::string_view> models = model_kind_names();
  models.insert(models.end(), {"banning", "stage", "auto"});
  EXPECT_NE(r.output.find(choice_list(models)), std::string::npos) << r.output;
  // LCM logs and publishing (tested on logs in tools/identify/tests/).
  EXPECT_NE(r.output.find(".lcmlog"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("--from"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("--publish"), std::string::npos) << r.output;
  // The plots (--out DIR), the adoption wait, the exit status.
  EXPECT_NE(r.output.find("loop_u_y.png"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("--no-wait"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("Exit status"), std::string::npos) << r.output;
}

TEST_F(IdentifyTool, PublishOnHxParamsIsOnlyForMem) {
  const MemParams truth = MemParams::paper_like();
  const auto u = testdata::paper_identification_input();
  std::vector<double> y = testdata::model_output(truth, u);
  write_csv(path("mem.csv"), u, y, 1e4);
  // Refused before any LCM is opened (any model on HX_MODEL: identify_publish_test.cpp, in a namespace).
  const ToolRun pi = run_tool(path("mem.csv") + " --model pi --publish --publish-on params");
  EXPECT_EQ(pi.exit_code, 2) << pi.output;
  EXPECT_NE(pi.output.find("only with --model mem"), std::string::npos) << pi.output;
  // A URL whose packets could leave the host is refused: tools/identify/tests/identify_publish_test.cpp,
  // inside a private network namespace.
  // A time range is for logs.
  EXPECT_EQ(run_tool(path("mem.csv") + " --model mem --to 1").exit_code, 2);
}

}  // namespace
}  // namespace hystloop
