// hystloop-identify --out DIR: the plots a user judges a fit by. The tool runs as a process on a
// recorded MEM loop; its data files are read back: measured and model columns, residual =
// measured - model on every row, the held-out branch marked where the fit stopped, one file per
// candidate of --model auto; the script names every figure, and the PNGs exist where gnuplot
// runs. The adoption verdict of --publish (AdoptionWatch) without any network.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "adoption_watch.hpp"
#include "lcm/status_counters.hpp"
#include "sensor_log_fixture.hpp"
#include "support/tool_run.hpp"

namespace hystloop {
namespace {

namespace fs = std::filesystem;
using namespace testlog;

const std::string kTool = HYSTLOOP_IDENTIFY_EXE;

struct Row {
  double t, u, y, model, residual;
  int heldout;
};

// The rows of a data file; fails the test on a malformed line.
std::vector<Row> read_rows(const fs::path& file) {
  std::vector<Row> rows;
  std::ifstream in(file);
  EXPECT_TRUE(in.good()) << file;
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream ss(line);
    std::string f[6];
    for (auto& x : f) ss >> x;
    EXPECT_FALSE(f[5].empty()) << file << ": " << line;
    auto num = [](const std::string& s) { return s == "NaN" ? std::nan("") : std::stod(s); };
    rows.push_back({num(f[0]), num(f[1]), num(f[2]), num(f[3]), num(f[4]), std::stoi(f[5])});
  }
  return rows;
}

std::string slurp(const fs::path& file) {
  std::ifstream in(file);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

bool is_png(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  char magic[8] = {};
  in.read(magic, 8);
  return in.good() && std::string(magic + 1, 3) == "PNG" && fs::file_size(file) > 1000;
}

// Where gnuplot is missing only the PNGs are (the data and the script are written all the same).
bool gnuplot_missing() { return std::system("command -v gnuplot >/dev/null 2>&1") != 0; }

// The first held-out row, checked: the flags are 0 up to it and 1 from it on.
std::size_t split_of(const std::vector<Row>& rows) {
  std::size_t split = rows.size();
  for (std::size_t i = 0; i < rows.size(); ++i) {
    if (rows[i].heldout == 1 && split == rows.size()) split = i;
    EXPECT_EQ(rows[i].heldout, i >= split ? 1 : 0) << "row " << i;
  }
  return split;
}

class IdentifyPlots : public ::testing::Test {
 protected:
  void SetUp() override { write_log(path("run.lcmlog"), mem_record(truth_, 0.5e-9)); }
  std::string path(const std::string& name) const { return scratch_.path(name); }
  testing::ToolRun run(const std::string& args) const {
    return testing::run_tool(kTool + " " + path("run.lcmlog") + " " + args);
  }
  testing::ScratchDir scratch_{"hystloop_identify_plots"};
  const MemParams truth_ = MemParams::paper_like();
};

TEST_F(IdentifyPlots, OneModelGivesLoopResidualAndHeldOutBranch) {
  const auto r = run("--model mem --out " + path("fit") + "/");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const fs::path dir = path("fit");
  EXPECT_NE(slurp(dir / "config.yaml").find("mem:"), std::string::npos);

  // The whole-record fit: measured and model agree to the noise, residual = measured - model.
  const std::vector<Row> fit = read_rows(dir / "fit_mem.dat");
  ASSERT_EQ(fit.size(), kTicks);
  std::size_t modelled = 0;
  for (const Row& row : fit) {
    EXPECT_EQ(row.heldout, 0);
    if (std::isnan(row.model)) {
      EXPECT_LT(row.t, 0.06) << "MEM has no state only before its first reversal";
      EXPECT_TRUE(std::isnan(row.residual));
      continue;
    }
    ++modelled;
    EXPECT_NEAR(row.residual, row.y - row.model, 1e-16) << row.t;
    EXPECT_LT(std::abs(row.residual), 5e-9) << row.t;
  }
  EXPECT_GT(modelled, kTicks * 9 / 10);

  // The held-out branch: MEM fitted on the first part, the rest marked and predicted.
  const std::vector<Row> held = read_rows(dir / "heldout_mem.dat");
  ASSERT_EQ(held.size(), kTicks);
  const std::size_t split = split_of(held);
  EXPECT_GT(split, kTicks * 6 / 10);
  EXPECT_LT(split, kTicks * 9 / 10);
  std::smatch m;
  ASSERT_TRUE(std::regex_search(r.output, m, std::regex(R"(held out from t = ([0-9.eE+-]+) s \(sample (\d+)\))")))
      << r.output;
  EXPECT_EQ(std::stoul(m[2].str()), split);
  double ss = 0.0;
  for (std::size_t i = split; i < held.size(); ++i) {
    EXPECT_NEAR(held[i].residual, held[i].y - held[i].model, 1e-16);
    ss += held[i].residual * held[i].residual;
  }
  EXPECT_LT(std::sqrt(ss / static_cast<double>(held.size() - split)), 3e-9);

  const std::string gp = slurp(dir / "plots.gp");
  for (const char* image : {"loop_u_y.png", "residual.png", "heldout_u_y.png"}) {
    EXPECT_NE(gp.find(std::string("set output '") + image + "'"), std::string::npos) << image << "\n" << gp;
    if (!gnuplot_missing()) {
      EXPECT_TRUE(is_png(dir / image)) << image << "\n" << r.output;
    }
  }
  EXPECT_EQ(gp.find("candidates.png"), std::string::npos) << "one model: nothing side by side";
  EXPECT_NE(gp.find("y [µm]"), std::string::npos);
  EXPECT_NE(gp.find("[nm]"), std::string::npos);
}

TEST_F(IdentifyPlots, AutoGivesOneCurvePerCandidateSideBySide) {
  fs::create_directories(path("auto"));  // an existing folder needs no trailing '/'
  const auto r = run("--model auto --out " + path("auto"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const fs::path dir = path("auto");
  std::smatch m;
  ASSERT_TRUE(std::regex_search(r.output, m, std::regex(R"(held out from sample (\d+) of (\d+); best: (\w+))")))
      << r.output;
  const std::size_t split = std::stoul(m[1].str());
  const std::string gp = slurp(dir / "plots.gp");
  std::size_t candidates = 0;
  std::vector<double> last_models;
  for (const std::string kind : {"mem", "pi", "katalenic", "linear"}) {
    // Every model the ranking scored has its curve, held out from the same sample.
    const bool ok = std::regex_search(r.output, std::regex("\\d+  " + kind + " +ok "));
    if (!ok) continue;
    ++candidates;
    const std::vector<Row> rows = read_rows(dir / ("fit_" + kind + ".dat"));
    ASSERT_EQ(rows.size(), kTicks) << kind;
    EXPECT_EQ(split_of(rows), split) << kind;
    for (const Row& row : rows) {
      if (!std::isnan(row.model)) {
        EXPECT_NEAR(row.residual, row.y - row.model, 1e-16) << kind;
      }
    }
    EXPECT_NE(gp.find("set title '" + kind + ": held-out "), std::string::npos) << kind << "\n" << gp;
    // Each file holds its own model: on the held-out rows it differs from the previous one's.
    std::vector<double> models;
    for (std::size_t i = split; i < rows.size(); ++i) models.push_back(rows[i].model);
    if (!last_models.empty()) {
      double largest = 0.0;
      for (std::size_t i = 0; i < models.size(); ++i) largest = std::max(largest, std::abs(models[i] - last_models[i]));
      EXPECT_GT(largest, 1e-12) << kind << ": the same curve as another model";
    }
    last_models = models;
  }
  EXPECT_GE(candidates, 3u) << r.output;
  EXPECT_NE(gp.find("set multiplot layout"), std::string::npos);
  EXPECT_NE(slurp(dir / "config.yaml").find(m[3].str() + ":"), std::string::npos);
  if (!gnuplot_missing()) {
    EXPECT_TRUE(is_png(dir / "candidates.png")) << r.output;
  }
}

TEST_F(IdentifyPlots, WithoutGnuplotTheDataAndScriptStayAndTheFitSucceeds) {
  const auto r = run("--model linear --out " + path("nognuplot") + "/ --gnuplot /nonexistent/gnuplot");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("gnuplot not found"), std::string::npos) << r.output;
  EXPECT_TRUE(fs::exists(path("nognuplot") + "/plots.gp"));
  EXPECT_EQ(read_rows(path("nognuplot") + "/fit_linear.dat").size(), kTicks);
  EXPECT_FALSE(fs::exists(path("nognuplot") + "/loop_u_y.png"));
  // --out FILE stays the snippet's file, no plots.
  const auto f = run("--model linear --out " + path("linear.yaml"));
  ASSERT_EQ(f.exit_code, 0) << f.output;
  EXPECT_NE(slurp(path("linear.yaml")).find("linear:"), std::string::npos);
  EXPECT_EQ(f.output.find("plots:"), std::string::npos) << f.output;
}

// --- the adoption verdict ---

service_status_t status(const std::string& process, const std::vector<std::pair<std::string, std::int64_t>>& counters) {
  service_status_t s{};
  s.process = process;
  s.n_counters = static_cast<std::int32_t>(counters.size());
  for (const auto& [n, v] : counters) {
    s.counter_names.push_back(n);
    s.counter_values.push_back(v);
  }
  return s;
}

TEST(AdoptionWatch, TheCompensatorsVersionInUseDecides) {
  AdoptionWatch w("compensator", 8);
  EXPECT_EQ(w.verdict(3, "HX_STATUS"), "no rig is running (nothing reported on HX_STATUS within 3 s)");
  w.on_status(status("bridge", {{"params_version", 8}}));  // another process's counter does not count
  EXPECT_FALSE(w.adopted());
  EXPECT_EQ(w.verdict(3, "HX_STATUS"),
            "not adopted within 3 s (no 'compensator' reported on HX_STATUS; heard: bridge)");
  w.on_status(status("compensator", {{"params_version", 7}, {"params_rejected", 2}}));
  EXPECT_EQ(w.verdict(3, "HX_STATUS"), "not adopted within 3 s ('compensator' in use: version 7)");
  w.on_status(status("compensator", {{"params_version", 7}, {"params_rejected", 3}}));
  EXPECT_EQ(w.verdict(3, "HX_STATUS"),
            "not adopted within 3 s ('compensator' in use: version 7; its params_rejected rose by 1)");
  w.on_command_version(8);  // the status counter, when there is one, is the compensator's own word
  EXPECT_FALSE(w.adopted());
  w.on_status(status("compensator", {{"params_version", 8}}));
  EXPECT_TRUE(w.adopted());
  EXPECT_EQ(w.verdict(3, "HX_STATUS"), "adopted by 'compensator' (version 8)");
}

TEST(AdoptionWatch, ASetForAnotherAxisWaitsOnThatAxissVersion) {
  AdoptionWatch w("compensator", 8, 1);  // a set for y
  w.on_status(status("compensator", {{"params_version", 8}, {"y_params_version", 7}}));
  EXPECT_FALSE(w.adopted()) << "x's version says nothing of y's";
  w.on_status(status("compensator", {{"params_version", 8}, {"y_params_version", 8}}));
  EXPECT_TRUE(w.adopted());
  EXPECT_EQ(params_version_counter(0), "params_version");
  EXPECT_EQ(params_version_counter(2), "z_params_version");
}

TEST(AdoptionWatch, CommandTicksTellTheVersionWhenTheStatusDoesNot) {
  AdoptionWatch w("comp2", 5);
  w.on_status(status("comp2", {{"samples", 100}}));
  EXPECT_EQ(w.verdict(2, "RIG_STATUS"), "not adopted within 2 s ('comp2' reported no version in use)");
  w.on_command_version(4);
  EXPECT_EQ(w.verdict(2, "RIG_STATUS"), "not adopted within 2 s ('comp2' in use: version 4)");
  w.on_command_version(5);
  EXPECT_TRUE(w.adopted());
  EXPECT_EQ(w.verdict(2, "RIG_STATUS"), "adopted by 'comp2' (version 5)");
}

}  // namespace
}  // namespace hystloop
