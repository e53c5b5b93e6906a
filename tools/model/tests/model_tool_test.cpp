// hystloop-model end to end: CSVs written by the test, the tool run as a process, its output read
// back and compared with the models run in-process; forward-then-inverse round trips; the YAML
// hystloop-identify writes (ident/params_yaml) read back with --params-file; every refusal gives
// exit code 2 and names file:line and column, or the parameter; --help lists everything.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include "models/csv_columns.hpp"
#include "ident/params_yaml.hpp"
#include "model_registry.hpp"
#include "models/banning_stage.hpp"
#include "models/katalenic.hpp"
#include "models/linear.hpp"
#include "models/mem.hpp"
#include "models/prandtl_ishlinskii.hpp"

namespace hystloop::model_tool {
namespace {

const std::string kTool = HYSTLOOP_MODEL_EXE;

struct ToolRun {
  int exit_code = -1;
  std::string out;  // stdout
  std::string err;  // stderr
};

std::string slurp(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

class ModelTool : public ::testing::Test {
 protected:
  // A fresh folder per test from mkdtemp: unique, and one level deep (a parameterised test's name
  // holds a '/', which made a nested folder whose parent TearDown left behind).
  void SetUp() override {
    std::string tmpl = (std::filesystem::temp_directory_path() / "hystloop_model_tool_XXXXXX").string();
    ASSERT_NE(::mkdtemp(tmpl.data()), nullptr) << "mkdtemp " << tmpl;
    dir_ = tmpl;
  }
  void TearDown() override {
    std::error_code ec;
    std::filesystem::remove_all(dir_, ec);
  }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }

  ToolRun run(const std::string& args) const {
    ToolRun r;
    const std::string err = path("stderr.txt");
    FILE* pipe = ::popen((kTool + " " + args + " 2>" + err).c_str(), "r");
    if (pipe == nullptr) return r;
    char buf[4096];
    std::size_t n = 0;
    while ((n = std::fread(buf, 1, sizeof buf, pipe)) > 0) r.out.append(buf, n);
    const int status = ::pclose(pipe);
    r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    r.err = slurp(err);
    return r;
  }

  std::string write_text(const std::string& name, const std::string& text) const {
    std::string p = path(name);
    std::ofstream(p) << text;
    return p;
  }

  std::string write_columns(const std::string& name, std::vector<std::string_view> names,
                            const std::vector<const std::vector<double>*>& cols) const {
    std::ofstream f(path(name));
    write_csv_columns(f, names, cols);
    return path(name);
  }

  std::filesystem::path dir_;
};

CsvColumns parse(const std::string& text, std::vector<std::string_view> names) {
  std::istringstream in(text);
  return read_csv_columns(in, "tool output", names);
}

// A drive with reversals, minor loops and a non-zero start, within +-250 V.
void make_drive(std::size_t n, std::vector<double>& t, std::vector<double>& u) {
  t.resize(n);
  u.resize(n);
  for (std::size_t k = 0; k < n; ++k) {
    const double s = static_cast<double>(k) / static_cast<double>(n);
    t[k] = 1e-4 * static_cast<double>(k);
    u[k] = 20.0 + 190.0 * (1.0 - 0.6 * s) * std::sin(2.0 * std::numbers::pi * 3.0 * s) +
           35.0 * std::sin(2.0 * std::numbers::pi * 23.0 * s);
  }
}

template <class Model>
std::vector<double> forward_in_process(Model model, const std::vector<double>& u) {
  model.reset(u.front());
  std::vector<double> y(u.size());
  for (std::size_t k = 0; k < u.size(); ++k) y[k] = model.forward(u[k]);
  return y;
}

struct RoundTripCase {
  const char* name;
  const char* params;
  double u_tolerance_V;
};

class ModelToolRoundTrip : public ModelTool, public ::testing::WithParamInterface<RoundTripCase> {};

TEST_P(ModelToolRoundTrip, ForwardThenInverseGivesTheInputBack) {
  const RoundTripCase c = GetParam();
  const std::string model = std::string(c.name).substr(0, std::string(c.name).find('_'));
  std::vector<double> t, u;
  make_drive(1500, t, u);
  const std::string u_csv = write_columns("u.csv", {"t", "u"}, {&t, &u});
  const ToolRun f = run("--model " + model + " " + c.params + " --forward " + u_csv + " --out " + path("y.csv"));
  ASSERT_EQ(f.exit_code, 0) << f.err;
  EXPECT_EQ(f.out, "");
  const CsvColumns fy = parse(slurp(path("y.csv")), {"t", "u", "y"});
  ASSERT_EQ(fy.rows(), u.size());
  EXPECT_EQ(fy.values[0], t);  // t and u are copied exactly
  EXPECT_EQ(fy.values[1], u);
  const std::vector<double>& y = fy.values[2];
  const auto [lo, hi] = std::minmax_element(y.begin(), y.end());
  EXPECT_GT(*hi - *lo, 1e-6) << "the drive should span a stroke of micrometres";

  const std::string y_csv = write_columns("y_ref.csv", {"t", "y_ref"}, {&t, &y});
  const ToolRun i = run("--model " + model + " " + c.params + " --inverse " + y_csv);
  ASSERT_EQ(i.exit_code, 0) << i.err;
  const CsvColumns iu = parse(i.out, {"t", "y_ref", "u"});
  ASSERT_EQ(iu.rows(), u.size());
  EXPECT_EQ(iu.values[1], y);
  double worst = 0.0;
  for (std::size_t k = 0; k < u.size(); ++k) worst = std::max(worst, std::abs(iu.values[2][k] - u[k]));
  EXPECT_LE(worst, c.u_tolerance_V) << model;
  RecordProperty("worst_u_error_V", format_number(worst));

  // Control: the inverse of the model with its default parameters does not give u back.
  const ToolRun d = run("--model " + model + " --inverse " + y_csv);
  ASSERT_EQ(d.exit_code, 0) << d.err;
  const CsvColumns du = parse(d.out, {"t", "y_ref", "u"});
  double control = 0.0;
  for (std::size_t k = 0; k < u.size(); ++k) control = std::max(control, std::abs(du.values[2][k] - u[k]));
  EXPECT_GT(control, 0.1) << model;
}

INSTANTIATE_TEST_SUITE_P(
    Models, ModelToolRoundTrip,
    ::testing::Values(RoundTripCase{"mem", "--param c1=4.5e-9 --param c2=2e-12 --param c3=1.1", 1e-11},
                      RoundTripCase{"pi", "--param count=12 --param range_V=260", 1e-11},
                      RoundTripCase{"pi_weights", "--param weights=4e-9,1e-9,1e-9,5e-10,5e-10 --param u_max=250",
                                    1e-11},
                      RoundTripCase{"katalenic", "--param k1=30 --param k2=0.02", 1e-11},
                      RoundTripCase{"linear", "--param gain=6e-9 --param offset=1e-7", 1e-11}),
    [](const auto& test) { return std::string(test.param.name); });

TEST_F(ModelTool, ForwardEqualsTheModelInProcess) {
  std::vector<double> t, u;
  make_drive(600, t, u);
  const std::string u_csv = write_columns("u.csv", {"t", "u"}, {&t, &u});
  const auto check = [&](const std::string& args, const std::vector<double>& expected) {
    const ToolRun r = run(args + " --forward " + u_csv);
    ASSERT_EQ(r.exit_code, 0) << args << "\n" << r.err;
    EXPECT_EQ(parse(r.out, {"t", "u", "y"}).values[2], expected) << args;
  };
  check("--model mem", forward_in_process(MemModel(MemParams::paper_like()), u));
  check("--model pi", forward_in_process(PiModel(pi_params_from_mem(MemParams::paper_like(), 15, 250.0)), u));
  check("--model katalenic", forward_in_process(KatalenicModel(KatalenicParams{}), u));
  check("--model linear", forward_in_process(LinearModel(LinearParams{}), u));
}

// Banning has dynamics: the tool takes dt from the t column, here deliberately uneven.
TEST_F(ModelTool, BanningForwardMatchesTheStageSteppedWithTheFilesTimes) {
  std::vector<double> t, u;
  make_drive(800, t, u);
  for (std::size_t k = 1; k < t.size(); ++k) t[k] = t[k - 1] + (k % 3 == 0 ? 50e-6 : 120e-6);
  const std::string u_csv = write_columns("u.csv", {"t", "u"}, {&t, &u});
  for (const bool paper_order : {false, true}) {
    BanningStageParams p;
    p.hysteresis.alpha = 0.015;
    if (paper_order) p.order = BanningOrder::kStageThenHysteresis;
    BanningStage stage(p);
    stage.reset(u[0]);
    std::vector<double> y = {stage.output()};
    for (std::size_t k = 1; k < u.size(); ++k) y.push_back(stage.step(u[k], t[k] - t[k - 1]));

    const ToolRun r =
        run("--model banning --param hysteresis.alpha=0.015 " +
            std::string(paper_order ? "--param order=stage_then_hysteresis " : "") + "--forward " + u_csv);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const std::vector<double> got = parse(r.out, {"t", "u", "y"}).values[2];
    ASSERT_EQ(got.size(), y.size());
    for (std::size_t k = 0; k < y.size(); ++k) ASSERT_EQ(got[k], y[k]) << "row " << k;
    // The resonant stage rings after each uneven step: a constant dt would give another answer.
    BanningStage uniform(p);
    uniform.reset(u[0]);
    double diff = 0.0;
    for (std::size_t k = 1; k < u.size(); ++k) diff = std::max(diff, std::abs(uniform.step(u[k], 1e-4) - y[k]));
    EXPECT_GT(diff, 1e-9);
  }
}

// The YAML hystloop-identify --out writes (its snippet functions) read back as parameters.
TEST_F(ModelTool, ReadsTheParamsFileHystloopIdentifyWrites) {
  std::vector<double> t, u;
  make_drive(400, t, u);
  const std::string u_csv = write_columns("u.csv", {"t", "u"}, {&t, &u});
  const auto check = [&](const std::string& yaml, const std::string& args, const std::vector<double>& expected) {
    const std::string file = write_text("params.yaml", "# written by hystloop-identify\n" + yaml);
    const ToolRun r = run("--params-file " + file + " " + args + " --forward " + u_csv);
    ASSERT_EQ(r.exit_code, 0) << yaml << r.err;
    EXPECT_EQ(parse(r.out, {"t", "u", "y"}).values[2], expected) << yaml;
  };
  const MemParams mem{4.1e-9, 2.3e-12, 1.05};
  check(to_yaml(mem), "", forward_in_process(MemModel(mem), u));
  check(to_yaml(mem), "--model mem", forward_in_process(MemModel(mem), u));
  MemParams overridden = mem;
  overridden.c3 = 1.3;
  check(to_yaml(mem), "--param c3=1.3", forward_in_process(MemModel(overridden), u));  // --param wins

  PiParams pi = PiParams::with_even_thresholds(4, 200.0);
  pi.weights = {3e-9, 1e-9, 0.5e-9, 0.25e-9};
  check(to_yaml(pi), "", forward_in_process(PiModel(pi), u));

  const LinearParams lin{5.5e-9, -2e-8};
  check(to_yaml(lin), "", forward_in_process(LinearModel(lin), u));

  KatalenicParams kat;
  kat.k1 = 25.0;
  kat.k2 = 0.03;
  kat.output_shaping = ShapingFunction::make_odd_polynomial({3.5e-9, 2e-15}, -300.0, 300.0);
  kat.output_shaping.domain_min = -300.0;
  kat.output_shaping.domain_max = 300.0;
  check(to_yaml(kat), "", forward_in_process(KatalenicModel(kat), u));

  ColemanHodgdonParams ch;
  ch.a = 8.0e-9;
  ch.b = 6.5e-9;
  ch.alpha = 0.01;
  SecondOrderStageParams st{9.0e7, 1.5e3};
  BanningStage stage(BanningStageParams{ch, st, BanningOrder::kHysteresisThenStage});
  stage.reset(u[0]);
  std::vector<double> y = {stage.output()};
  for (std::size_t k = 1; k < u.size(); ++k) y.push_back(stage.step(u[k], t[k] - t[k - 1]));
  check(to_yaml(ch, &st), "", y);
}

TEST_F(ModelTool, ReadsStandardInputWritesStandardOutputAndSaysWhichColumnsItIgnores) {
  write_text("u.csv", "# bench run 3\nexperiment,t,y,u\na,0,0,0\na, 0.001 , 1e-7 , 50\n\nb,0.002,2e-7,-25.5\n");
  const ToolRun r = run("--model linear --param gain=0.5 --forward - < " + path("u.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.out, "t,u,y\n0,0,0\n0.001,50,25\n0.002,-25.5,-12.75\n");
  EXPECT_NE(r.err.find("<stdin>:2: ignoring columns 'experiment', 'y'"), std::string::npos) << r.err;
}

struct Refusal {
  std::string args;     // {in} is replaced by the input file
  std::string csv;      // input file content
  std::string message;  // expected on stderr
};

// One case per kind of refusal (the reader's and the tables' messages are checked in detail
// in-process by model_tool_core_test); each is a process start, which is slow under the sanitizer.
TEST_F(ModelTool, EveryRefusalExitsWithTwoAndNamesWhere) {
  const std::string ok = "t,u\n0,0\n0.001,10\n";
  const std::vector<Refusal> cases = {
      {"--model mem --forward {in}", "t,u\n0,0\n0.001,abc\n", "{in}:3: column 'u': expected a number, got 'abc'"},
      {"--model mem --forward {in}", "", "{in}:1: empty file: expected a header row 't,u'"},
      {"--model mem --forward {in}", "0,0\n0.001,10\n", "{in}:1: missing header row: expected column names 't,u'"},
      {"--model mem --forward {in}", "t,v\n0,0\n", "{in}:1: header 't,v' lacks column 'u'"},
      {"--model mem --inverse {in}", ok, "{in}:1: header 't,u' lacks column 'y_ref' (expected 't,y_ref'"},
      {"--model mem --forward {in}", "t,u\n0,0\n0.001,inf\n",
       "{in}:3: column 'u': expected a finite number, got 'inf'"},
      {"--model mem --forward {in}", "t,u\n0,0\n0.001,1,2\n", "{in}:3: 3 fields, the header has 2"},
      {"--model mem --forward {in}", "t,u\n", "{in}:1: no data rows after the header"},
      {"--model banning --forward {in}", "t,u\n0,0\n0.001,1\n0.001,2\n",
       "{in}:4: column 't': must increase, got 0.001 after 0.001 (line 3)"},
      {"--model banning --inverse {in}", "t,y_ref\n0,0\n", "--inverse: model banning has no inverse"},
      {"--model mem --forward --param c4=1 {in}", ok,
       "--param c4=1: unknown parameter 'c4' of model mem; did you mean 'c1'? (valid: c1, c2, c3)"},
      {"--model mem --forward --param c1=5e-9x {in}", ok, "--param c1=5e-9x: expected a number, got '5e-9x'"},
      {"--model mem --forward --param c1 {in}", ok, "--param c1: expected NAME=VALUE"},
      {"--model mem --forward --param c3=-1 {in}", ok, "model mem: c3: must be > 0 (got -1)"},
      {"--model banning --forward --param hysteresis.b=1e-8 {in}", ok, "model banning: hysteresis.b:"},
      {"--model pi --forward --param n=40 {in}", ok, "model pi: count: must be in [1, 32] (got 40)"},
      {"--model pi --forward --param thresholds=0,10 {in}", ok, "model pi: thresholds: given without weights"},
      {"--model pi --forward --param weights=-1e-9 {in}", ok, "model pi: weights[0]:"},
      {"--model memm --forward {in}", ok, "--model: unknown model 'memm'; did you mean 'mem'?"},
      {"--forward {in}", ok, "give --model"},
      {"--model mem {in}", ok, "choose --forward"},
      {"--model mem --forward --inverse {in}", ok, "excludes"},
      {"--model mem --forward --no-such-option {in}", ok, "--no-such-option"},
      {"--model mem --forward {in}.missing", ok, "{in}.missing: cannot open the input file"},
      {"--model mem --forward --params-file {in}.missing {in}", ok, "{in}.missing: cannot open the parameters file"},
      {"--model mem --forward {in} --out " + path("no/such/dir/y.csv"), ok, "no/such/dir/y.csv: cannot write"},
  };
  for (std::size_t i = 0; i < cases.size(); ++i) {
    const std::string in = write_text("in" + std::to_string(i) + ".csv", cases[i].csv);
    const auto fill = [&](std::string s) {
      for (std::size_t p; (p = s.find("{in}")) != std::string::npos;) s.replace(p, 4, in);
      return s;
    };
    const ToolRun r = run(fill(cases[i].args));
    EXPECT_EQ(r.exit_code, 2) << cases[i].args << "\n" << r.err;
    EXPECT_NE(r.err.find(fill(cases[i].message)), std::string::npos)
        << cases[i].args << "\nexpected: " << fill(cases[i].message) << "\ngot: " << r.err;
    EXPECT_EQ(r.out, "") << cases[i].args;  // nothing half-written on stdout
  }
}

TEST_F(ModelTool, ParamsFileRefusalsNameTheFileAndKey) {
  const std::string in = write_text("u.csv", "t,u\n0,0\n");
  const std::string bad = write_text("bad.yaml", "mem:\n  c1: 5e-9\n  c2: lots\n");
  ToolRun r = run("--params-file " + bad + " --forward " + in);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find(bad + ": mem.c2: expected a number, got 'lots'"), std::string::npos) << r.err;
  const std::string typo = write_text("typo.yaml", "linear: {gian: 5e-9}\n");
  r = run("--params-file " + typo + " --forward " + in);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find(typo + ": linear.gian: unknown parameter 'gian' of model linear; did you mean 'gain'?"),
            std::string::npos)
      << r.err;
  const std::string other = write_text("other.yaml", "pi: {n: 3}\n");
  r = run("--params-file " + other + " --model mem --forward " + in);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find(other + ": no 'mem' section (it has: pi)"), std::string::npos) << r.err;
}

// A finite input the model cannot map (MEM's p^c3 overflows) is a failure of the run, not of
// the file: exit 1, naming the row.
TEST_F(ModelTool, ANonFiniteResultExitsWithOneNamingTheRow) {
  const std::string in = write_text("u.csv", "t,u\n0,0\n0.001,1e300\n");
  const ToolRun r = run("--model mem --forward " + in + " --out " + path("y.csv"));
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find(in + ":3: model mem gave a non-finite y for u = 1e+300"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(path("y.csv")));
}

TEST_F(ModelTool, NoOutputFileIsWrittenWhenTheInputIsRefused) {
  const std::string in = write_text("u.csv", "t,u\n0,0\n0.001,x\n");
  const ToolRun r = run("--model mem --forward " + in + " --out " + path("y.csv"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_FALSE(std::filesystem::exists(path("y.csv")));
}

TEST_F(ModelTool, HelpListsEveryModelAndParameterWithUnitAndDefault) {
  const ToolRun r = run("--help");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (const ModelEntry* m : model_registry()) {
    EXPECT_NE(r.out.find("  " + std::string(m->name) + ": "), std::string::npos) << m->name;
    for (const ParamInfo& p : m->parameters()) {
      const std::size_t at = r.out.find("    " + p.name + " ");
      ASSERT_NE(at, std::string::npos) << m->name << " " << p.name;
      const std::string line = r.out.substr(at, r.out.find('\n', at) - at);
      EXPECT_NE(line.find("[" + p.unit + "]"), std::string::npos) << line;
      EXPECT_NE(line.find("default " + p.default_text), std::string::npos) << line;
    }
  }
  for (const char* name :
       {"c1", "c2", "c3", "hysteresis.alpha", "stage.k", "k1", "k2", "output_shaping.gain", "count (or n)",
        "range_V (or u_max)", "weights", "thresholds", "gain", "offset", "--params-file", "--forward", "--inverse"}) {
    EXPECT_NE(r.out.find(name), std::string::npos) << name;
  }
}

}  // namespace
}  // namespace hystloop::model_tool
