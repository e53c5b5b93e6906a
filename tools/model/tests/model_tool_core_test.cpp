// hystloop-model's pieces in-process: strict number parsing, the CSV reader (every refusal names
// its line and column) and writer (exact round trip), the parameter tables and the registry
// (unknown names, aliases, the model's own validation), and the params file.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "models/csv_columns.hpp"
#include "model_registry.hpp"
#include "models/katalenic.hpp"
#include "models/mem.hpp"
#include "models/prandtl_ishlinskii.hpp"
#include "models/param_table.hpp"
#include "params_file.hpp"

namespace hystloop::model_tool {
namespace {

constexpr std::string_view kTU[] = {"t", "u"};

CsvColumns read(const std::string& text) {
  std::istringstream in(text);
  return read_csv_columns(in, "in.csv", kTU);
}

// The CsvError message for `text`, or "" if it was accepted.
std::string refusal(const std::string& text) {
  try {
    read(text);
  } catch (const CsvError& e) {
    return e.what();
  }
  return "";
}

TEST(StrictNumber, AcceptsCNotationOnly) {
  double v = 0.0;
  EXPECT_TRUE(parse_finite_double("1.5", v));
  EXPECT_EQ(v, 1.5);
  EXPECT_TRUE(parse_finite_double("  -2.5e-9 ", v));
  EXPECT_EQ(v, -2.5e-9);
  EXPECT_TRUE(parse_finite_double("+4", v));
  EXPECT_EQ(v, 4.0);
  EXPECT_TRUE(parse_finite_double(".5", v));
  EXPECT_EQ(v, 0.5);
  std::string why;
  for (const char* bad : {"", " ", "1.5x", "1,5", "abc", "0x10", "1e", "--1", "+-1", "+", "1 2"}) {
    EXPECT_FALSE(parse_finite_double(bad, v, &why)) << bad;
    EXPECT_EQ(why, "expected a number") << bad;
  }
  for (const char* bad : {"nan", "inf", "-inf", "1e999", "-1e400"}) {
    EXPECT_FALSE(parse_finite_double(bad, v, &why)) << bad;
    EXPECT_EQ(why, "expected a finite number") << bad;
  }
}

TEST(CsvColumnsRead, ReadsRequestedColumnsInAnyOrderAndListsTheOthers) {
  const CsvColumns c = read(
      "\xEF\xBB\xBF# recorded\r\n"
      "y, u ,t\r\n\n1e-9, 2.5 , 0\r\n2e-9,-3,0.001\n# end\n");
  ASSERT_EQ(c.rows(), 2u);
  EXPECT_EQ(c.values[0], (std::vector<double>{0.0, 0.001}));
  EXPECT_EQ(c.values[1], (std::vector<double>{2.5, -3.0}));
  EXPECT_EQ(c.lines, (std::vector<std::size_t>{4, 5}));
  EXPECT_EQ(c.header_line, 2u);
  EXPECT_EQ(c.ignored, (std::vector<std::string>{"y"}));
}

TEST(CsvColumnsRead, RefusesEachMalformedFileNamingLineAndColumn) {
  EXPECT_EQ(refusal(""), "in.csv:1: empty file: expected a header row 't,u'");
  EXPECT_EQ(refusal("# only a comment\n\n"), "in.csv:2: no header row: expected a header row 't,u'");
  EXPECT_EQ(refusal("0,1\n1,2\n"), "in.csv:1: missing header row: expected column names 't,u', got '0,1'");
  EXPECT_EQ(refusal("t,x\n0,1\n"), "in.csv:1: header 't,x' lacks column 'u' (expected 't,u', SI units)");
  EXPECT_EQ(refusal("time,volts\n0,1\n"),
            "in.csv:1: header 'time,volts' lacks column 't', 'u' (expected 't,u', SI units)");
  EXPECT_EQ(refusal("t,u,u\n0,1,2\n"), "in.csv:1: header names column 'u' twice");
  EXPECT_EQ(refusal("t,u\n"), "in.csv:1: no data rows after the header");
  EXPECT_EQ(refusal("t,u\n0,1\n0.1,abc\n"), "in.csv:3: column 'u': expected a number, got 'abc'");
  EXPECT_EQ(refusal("t,u\n0,1\n0.1,2.0.0\n"), "in.csv:3: column 'u': expected a number, got '2.0.0'");
  EXPECT_EQ(refusal("t,u\n0,1\n,2\n"), "in.csv:3: column 't': expected a number, got ''");
  EXPECT_EQ(refusal("t,u\n0,nan\n"), "in.csv:2: column 'u': expected a finite number, got 'nan'");
  EXPECT_EQ(refusal("t,u\n0,1\n1e400,1\n"), "in.csv:3: column 't': expected a finite number, got '1e400'");
  EXPECT_EQ(refusal("t,u\n0,1\n0.1,2,3\n"), "in.csv:3: 3 fields, the header has 2");
  EXPECT_EQ(refusal("t,u\n0,1\n0.1\n"), "in.csv:3: 1 field, the header has 2");
  EXPECT_EQ(refusal("t,u,y\n0,1,junk\n"), "");  // an ignored column is not parsed
}

TEST(CsvColumnsRead, RequireIncreasingNamesTheRow) {
  const CsvColumns c = read("t,u\n0,1\n0.1,2\n\n0.1,3\n");
  try {
    require_increasing(c, 0, "in.csv");
    FAIL() << "accepted a repeated t";
  } catch (const CsvError& e) {
    EXPECT_EQ(std::string(e.what()), "in.csv:5: column 't': must increase, got 0.1 after 0.1 (line 3)");
    EXPECT_EQ(e.line(), 5u);
  }
  EXPECT_NO_THROW(require_increasing(read("t,u\n0,1\n0.1,2\n"), 0, "in.csv"));
}

TEST(CsvColumnsWrite, RoundTripsEveryDoubleExactly) {
  std::mt19937_64 rng(42);
  std::uniform_real_distribution<double> mantissa(-1.0, 1.0);
  std::uniform_int_distribution<int> exponent(-300, 300);
  std::vector<double> t(500), u(500);
  for (std::size_t k = 0; k < t.size(); ++k) {
    t[k] = static_cast<double>(k) * 1e-4 + 1e-4 / 3.0;
    u[k] = std::ldexp(mantissa(rng), exponent(rng));
  }
  u[0] = std::numeric_limits<double>::denorm_min();
  u[1] = -0.0;
  u[2] = std::numeric_limits<double>::max();
  std::ostringstream out;
  const std::vector<double>* cols[] = {&t, &u};
  write_csv_columns(out, kTU, cols);
  EXPECT_EQ(out.str().substr(0, 4), "t,u\n");
  const CsvColumns back = read(out.str());
  ASSERT_EQ(back.rows(), t.size());
  for (std::size_t k = 0; k < t.size(); ++k) {
    EXPECT_EQ(back.values[0][k], t[k]) << k;
    EXPECT_EQ(back.values[1][k], u[k]) << k;
  }
  EXPECT_TRUE(std::signbit(back.values[1][1]));
}

// ---- parameters --------------------------------------------------------------------------------

Assignment param(const std::string& text) { return split_assignment(text, "--param"); }

std::string configure_error(std::string_view model, const std::vector<std::string>& params) {
  try {
    std::vector<Assignment> a;
    a.reserve(params.size());
    for (const auto& p : params) a.push_back(param(p));
    find_model(model)->configure(a);
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

TEST(ModelRegistry, HasEveryModelWithDefaultsThatValidate) {
  for (const char* name : {"mem", "banning", "katalenic", "pi", "linear"}) {
    const ModelEntry* m = find_model(name);
    ASSERT_NE(m, nullptr) << name;
    EXPECT_EQ(m->name, name);
    EXPECT_FALSE(m->parameters().empty()) << name;
    EXPECT_NO_THROW(m->configure({})) << name;
    EXPECT_EQ(m->has_inverse, std::string(name) != "banning") << name;
    EXPECT_EQ(m->uses_time, std::string(name) == "banning") << name;
  }
  EXPECT_EQ(find_model("Mem"), nullptr);
  EXPECT_EQ(model_registry().size(), 5u);
}

TEST(ModelRegistry, RefusesUnknownNamesWithTheValidOnesAndALikelyOne) {
  EXPECT_EQ(configure_error("mem", {"c4=1"}),
            "--param c4=1: unknown parameter 'c4' of model mem; did you mean 'c1'? (valid: c1, c2, c3)");
  EXPECT_EQ(configure_error("banning", {"hysteresis.alhpa=0.01"}).find("did you mean 'hysteresis.alpha'?") !=
                std::string::npos,
            true);
  const std::string far = configure_error("linear", {"frequency=3"});
  EXPECT_EQ(far, "--param frequency=3: unknown parameter 'frequency' of model linear (valid: gain, offset)");
}

TEST(ModelRegistry, ParsesValuesStrictly) {
  EXPECT_EQ(configure_error("mem", {"c1=5e-9junk"}), "--param c1=5e-9junk: expected a number, got '5e-9junk'");
  EXPECT_EQ(configure_error("mem", {"c1=inf"}), "--param c1=inf: expected a finite number, got 'inf'");
  EXPECT_EQ(configure_error("mem", {"c1"}), "--param c1: expected NAME=VALUE (e.g. c1=5e-9), got 'c1'");
  EXPECT_EQ(configure_error("pi", {"n=15.5"}), "--param n=15.5: expected a whole number >= 0, got '15.5'");
  EXPECT_EQ(configure_error("pi", {"n=-3"}), "--param n=-3: expected a whole number >= 0, got '-3'");
  EXPECT_EQ(configure_error("pi", {"weights=1e-9,x"}), "--param weights=1e-9,x: entry 1: expected a number, got 'x'");
  EXPECT_EQ(configure_error("banning", {"order=sideways"}),
            "--param order=sideways: expected one of hysteresis_then_stage|stage_then_hysteresis, got 'sideways'");
  EXPECT_EQ(configure_error("katalenic", {"output_shaping.coefficients=1,2,3,4,5,6,7,8,9"}),
            "--param output_shaping.coefficients=1,2,3,4,5,6,7,8,9: at most 8 coefficients (degree 7), got 9");
  EXPECT_EQ(configure_error("mem", {" c1 = 4e-9 "}), "");  // spaces around name and value are fine
}

TEST(ModelRegistry, TheModelsOwnValidationNamesTheField) {
  const auto field_of = [](std::string_view model, const std::vector<std::string>& params) {
    std::vector<Assignment> a;
    a.reserve(params.size());
    for (const auto& p : params) a.push_back(param(p));
    try {
      find_model(model)->configure(a);
    } catch (const ParameterError& e) {
      return e.field();
    }
    return std::string("(accepted)");
  };
  EXPECT_EQ(field_of("mem", {"c3=-1"}), "c3");
  EXPECT_EQ(field_of("mem", {"c1=0"}), "c1");
  EXPECT_EQ(field_of("linear", {"gain=0"}), "gain");
  EXPECT_EQ(field_of("katalenic", {"k1=-1"}), "k1");
  EXPECT_EQ(field_of("katalenic", {"output_shaping.gain=-1"}).rfind("output_shaping", 0), 0u);
  EXPECT_EQ(field_of("banning", {"hysteresis.alpha=-1"}), "hysteresis.alpha");
  EXPECT_EQ(field_of("banning", {"stage.k=0"}), "stage.k");
  EXPECT_EQ(field_of("pi", {"weights=-1e-9,2e-9"}), "weights[0]");
  EXPECT_EQ(field_of("pi", {"thresholds=0,1"}), "thresholds");
  // n and u_max are older spellings of count and range_V: accepted, the error names the field.
  EXPECT_EQ(field_of("pi", {"n=0"}), "count");
  EXPECT_EQ(field_of("pi", {"count=33"}), "count");
  EXPECT_EQ(field_of("pi", {"u_max=-5"}), "range_V");
  EXPECT_EQ(field_of("pi", {"range_V=0"}), "range_V");
  EXPECT_EQ(field_of("pi", {"n=3", "weights=1e-9,1e-9"}), "count");
  EXPECT_EQ(field_of("pi", {"weights=1e-9,1e-9", "thresholds=0,1,2"}), "weights");
  EXPECT_EQ(field_of("pi", {"count=2", "weights=1e-9,1e-9", "thresholds=0,10"}), "(accepted)");
  EXPECT_EQ(configure_error("mem", {"c3=-1"}), "c3: must be > 0 (got -1)");
}

// The PI built from count/range_V (here by their older spellings) is the project's MEM-matched baseline; checked
// through its output.
TEST(ModelRegistry, PiFromSizeAndRangeIsTheMemMatchedBaseline) {
  const auto run = find_model("pi")->configure({param("n=7"), param("u_max=200")});
  const std::vector<double> u = {0.0, 120.0, 200.0, -60.0, 30.0};
  const std::vector<double> t = {0, 1, 2, 3, 4};
  PiModel reference(pi_params_from_mem(MemParams::paper_like(), 7, 200.0));
  reference.reset(u[0]);
  const std::vector<double> y = run->forward(t, u);
  for (std::size_t k = 0; k < u.size(); ++k) EXPECT_EQ(y[k], reference.forward(u[k])) << k;

  // Explicit weights over even thresholds.
  const auto run2 = find_model("pi")->configure({param("weights=4e-9,1e-9,1e-9"), param("u_max=150")});
  PiParams p = PiParams::with_even_thresholds(3, 150.0);
  p.weights[0] = 4e-9;
  p.weights[1] = 1e-9;
  p.weights[2] = 1e-9;
  PiModel ref2(p);
  ref2.reset(u[0]);
  const std::vector<double> y2 = run2->forward(t, u);
  for (std::size_t k = 0; k < u.size(); ++k) EXPECT_EQ(y2[k], ref2.forward(u[k])) << k;
}

TEST(ModelRegistry, LaterAssignmentsOverrideEarlierOnes) {
  const auto run = find_model("linear")->configure({param("gain=1"), param("gain=2"), param("offset=0.5")});
  EXPECT_EQ(run->forward({0.0}, {3.0}), std::vector<double>{6.5});
  EXPECT_EQ(run->inverse({0.0}, {6.5}), std::vector<double>{3.0});
}

TEST(ModelRegistry, BanningRefusesInverseInProcessToo) {
  const auto run = find_model("banning")->configure({});
  EXPECT_THROW(run->inverse({0.0}, {0.0}), std::logic_error);
}

// The hint a refused --inverse gives lists the registry's models that have an inverse, no other.
TEST(ModelRegistry, InvertibleNamesAreTheModelsWithAnInverse) {
  std::string expected;
  for (const ModelEntry* m : model_registry()) {
    if (m->has_inverse) expected += (expected.empty() ? "" : ", ") + std::string(m->name);
  }
  EXPECT_EQ(invertible_model_names(), expected);
  EXPECT_EQ(invertible_model_names(), "mem, pi, katalenic, linear");
  EXPECT_EQ(invertible_model_names("|"), "mem|pi|katalenic|linear");
}

TEST(ModelRegistry, HelpListsEveryModelParameterUnitAndDefault) {
  const std::string help = models_help();
  for (const ModelEntry* m : model_registry()) {
    EXPECT_NE(help.find("  " + std::string(m->name) + ": "), std::string::npos) << m->name;
    for (const ParamInfo& p : m->parameters()) {
      EXPECT_NE(help.find("    " + p.name + " "), std::string::npos) << p.name;
      EXPECT_NE(help.find("[" + p.unit + "]"), std::string::npos) << p.name;
      EXPECT_NE(help.find("default " + p.default_text), std::string::npos) << p.name;
    }
  }
  EXPECT_NE(help.find("default 5e-09"), std::string::npos);  // MEM c1 from MemParams{}
  EXPECT_NE(help.find("count (or n)"), std::string::npos);
  EXPECT_NE(help.find("range_V (or u_max)"), std::string::npos);
}

// ---- params file -------------------------------------------------------------------------------

class ParamsFileTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() / ("hystloop_model_core_" + std::to_string(::getpid()) + "_" +
                                                     ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ec;
    std::filesystem::remove_all(dir_, ec);
  }
  std::string write(const std::string& name, const std::string& text) {
    std::string p = (dir_ / name).string();
    std::ofstream(p) << text;
    return p;
  }
  std::string error(const std::string& path, std::string_view model) {
    try {
      read_params_file(path, model);
    } catch (const ParamsFileError& e) {
      return e.what();
    }
    return "";
  }
  std::filesystem::path dir_;
};

TEST_F(ParamsFileTest, FlattensNestedMapsAndListsIntoAssignments) {
  const std::string p =
      write("p.yaml",
            "# written by hystloop-identify\n"
            "bridge: {u_max_V: 250}\n"
            "katalenic:\n  k1: 30  # [V]\n  output_shaping: {kind: polynomial, coefficients: [0, 3e-9, "
            "0, 1e-15], domain_min: -300, domain_max: 300}\n");
  const ParamsFile f = read_params_file(p, "");
  EXPECT_EQ(f.model, "katalenic");
  ASSERT_EQ(f.assignments.size(), 5u);
  EXPECT_EQ(f.assignments[0].name, "k1");
  EXPECT_EQ(f.assignments[0].value, "30");
  EXPECT_EQ(f.assignments[0].origin, p + ": katalenic.k1");
  EXPECT_EQ(f.assignments[2].name, "output_shaping.coefficients");
  EXPECT_EQ(f.assignments[2].value, "0,3e-9,0,1e-15");
  EXPECT_NO_THROW(find_model("katalenic")->configure(f.assignments));
}

TEST_F(ParamsFileTest, RefusesWithTheFileAndKey) {
  EXPECT_EQ(error((dir_ / "missing.yaml").string(), "mem"),
            (dir_ / "missing.yaml").string() + ": cannot open the parameters file");
  const std::string two = write("two.yaml", "mem: {c1: 5e-9}\npi: {n: 3}\n");
  EXPECT_EQ(error(two, ""), two + ": several model sections (mem, pi): choose one with --model");
  EXPECT_EQ(read_params_file(two, "pi").model, "pi");
  EXPECT_EQ(error(two, "linear"), two + ": no 'linear' section (it has: mem, pi)");
  const std::string none = write("none.yaml", "bridge: {u_max_V: 250}\n");
  EXPECT_EQ(error(none, ""), none + ": no model section (expected one of mem, pi, katalenic, linear, banning)");
  const std::string broken = write("broken.yaml", "mem:\n  c1: [1, 2\n");
  EXPECT_EQ(error(broken, "mem").rfind(broken + ":", 0), 0u);
  EXPECT_NE(error(broken, "mem").find("not valid YAML"), std::string::npos);
  const std::string empty_value = write("null.yaml", "mem:\n  c1:\n");
  EXPECT_EQ(error(empty_value, "mem"), empty_value + ": mem.c1: no value");
  const std::string scalar = write("scalar.yaml", "mem: 5\n");
  EXPECT_EQ(error(scalar, "mem"), scalar + ": mem: expected a map of parameter names to values");

  // Malformed values and unknown keys are the table's refusals, named by file and key.
  const std::string bad = write("bad.yaml", "mem: {c1: abc}\n");
  try {
    find_model("mem")->configure(read_params_file(bad, "mem").assignments);
    FAIL();
  } catch (const AssignmentError& e) {
    EXPECT_EQ(std::string(e.what()), bad + ": mem.c1: expected a number, got 'abc'");
  }
  const std::string typo = write("typo.yaml", "mem: {c11: 5e-9}\n");
  try {
    find_model("mem")->configure(read_params_file(typo, "mem").assignments);
    FAIL();
  } catch (const AssignmentError& e) {
    EXPECT_NE(std::string(e.what()).find(typo + ": mem.c11: unknown parameter 'c11' of model mem; did you mean 'c1'?"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace hystloop::model_tool
