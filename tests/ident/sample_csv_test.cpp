// CSV reading: columns by name, experiments, errors naming line and column; YAML snippets.
#include "ident/sample_csv.hpp"

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <sstream>

#include "ident/params_yaml.hpp"

namespace hystloop {
namespace {

SampleTable parse(const std::string& text) {
  std::istringstream in(text);
  return parse_sample_csv(in, "x.csv");
}

TEST(SampleCsv, ReadsColumnsByNameInAnyOrder) {
  const SampleTable t = parse("# comment\ny, U ,t,extra\n1e-9,2.5,0,a\n\n2e-9,3.5,0.0001,b\r\n");
  ASSERT_EQ(t.t.size(), 2u);
  EXPECT_DOUBLE_EQ(t.u[1], 3.5);
  EXPECT_DOUBLE_EQ(t.y[0], 1e-9);
  EXPECT_DOUBLE_EQ(t.t[1], 1e-4);
  EXPECT_TRUE(t.experiment.empty());
  EXPECT_NEAR(sample_rate_Hz(t.t), 1e4, 1e-6);
}

TEST(SampleCsv, GroupsExperimentsInOrderOfAppearance) {
  const SampleTable t = parse("experiment,t,u,y\nb,0,1,1e-9\na,0,2,2e-9\nb,1,3,3e-9\n");
  const auto groups = split_experiments(t);
  ASSERT_EQ(groups.size(), 2u);
  EXPECT_EQ(groups[0].experiment.front(), "b");
  EXPECT_EQ(groups[0].u, (std::vector<double>{1.0, 3.0}));
  EXPECT_EQ(groups[1].u, (std::vector<double>{2.0}));
}

TEST(SampleCsv, ErrorsNameFileLineAndColumn) {
  auto message = [](const std::string& text) {
    try {
      parse(text);
    } catch (const CsvError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(message("t,u,y\n0,1,2e-9\n0,1,x2\n"), "x.csv:3: column 'y': expected a number, got 'x2'");
  EXPECT_EQ(message("t,u,y\n0,1\n"), "x.csv:2: 2 fields, the header has 3");
  EXPECT_EQ(message("t,v,y\n0,1,2e-9\n"), "x.csv:1: header 't,v,y' lacks column 'u' (expected 't,u,y', SI units)");
  EXPECT_EQ(message("t,u,y\n"), "x.csv:1: no data rows after the header");
  EXPECT_EQ(message(""), "x.csv:1: empty file: expected a header row 't,u,y'");
  EXPECT_EQ(message("0,1,2e-9\n"), "x.csv:1: missing header row: expected column names 't,u,y', got '0,1,2e-9'");
  EXPECT_EQ(message("t,u,T,y\n0,1,2,3e-9\n"), "x.csv:1: header names column 'T' twice");
  EXPECT_EQ(message("t,u,y\n0,,1\n"), "x.csv:2: column 'u': expected a number, got ''");
  EXPECT_THROW(read_sample_csv("/nonexistent/file.csv"), CsvError);
}

// Values beyond physical sanity (the probe scaled a record by 1e300) are refused where the file,
// line and column can be named, not fitted into Inf and NaN.
TEST(SampleCsv, ValuesBeyondTheSanityBoundsNameLineAndColumn) {
  auto message = [](const std::string& text) {
    try {
      parse(text);
    } catch (const CsvError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(message("t,u,y\n0,10000,-1\n"), "no error");  // the bounds themselves are allowed
  EXPECT_EQ(message("t,u,y\n0,1,2e-9\n0,2.5e302,3e-9\n"),
            "x.csv:3: column 'u': 2.5e+302 V is beyond the sanity bound +-10000 V");
  EXPECT_EQ(message("t,y,u\n0,0,1\n0,-1.5,1\n"), "x.csv:3: column 'y': -1.5 m is beyond the sanity bound +-1 m");
  EXPECT_EQ(message("t,u,y\n0,inf,0\n"), "x.csv:2: column 'u': expected a finite number, got 'inf'");
}

TEST(ParamsYaml, KeysAreTheParameterNamesAndValuesRoundTrip) {
  MemParams m;
  m.c1 = 4.123456789012345e-9;
  const YAML::Node mem = YAML::Load(to_yaml(m));
  EXPECT_DOUBLE_EQ(mem["mem"]["c1"].as<double>(), m.c1);
  EXPECT_DOUBLE_EQ(mem["mem"]["c3"].as<double>(), m.c3);
  const SecondOrderStageParams stage{};
  const YAML::Node ban = YAML::Load(to_yaml(ColemanHodgdonParams{}, &stage));
  EXPECT_DOUBLE_EQ(ban["banning"]["hysteresis"]["alpha"].as<double>(), ColemanHodgdonParams{}.alpha);
  EXPECT_DOUBLE_EQ(ban["banning"]["stage"]["k"].as<double>(), stage.k);
  // ... and the compensator's stage section, which it inverts.
  EXPECT_EQ(ban["stage"]["kind"].as<std::string>(), "second_order");
  EXPECT_DOUBLE_EQ(ban["stage"]["c"].as<double>(), stage.c);
  const YAML::Node kat = YAML::Load(to_yaml(KatalenicParams{}));
  EXPECT_DOUBLE_EQ(kat["katalenic"]["k1"].as<double>(), KatalenicParams{}.k1);
  EXPECT_EQ(kat["katalenic"]["output_shaping"]["kind"].as<std::string>(), "linear");
  PiParams pi = PiParams::with_even_thresholds(3, 100.0);
  pi.weights = {1e-9, 2e-10, 1e-10};
  const YAML::Node p = YAML::Load(to_yaml(pi));
  EXPECT_EQ(p["pi"]["weights"].size(), 3u);
  EXPECT_DOUBLE_EQ(p["pi"]["thresholds"][2].as<double>(), pi.thresholds[2]);
  const YAML::Node l = YAML::Load(to_yaml(LinearParams{}));
  EXPECT_DOUBLE_EQ(l["linear"]["gain"].as<double>(), LinearParams{}.gain);
}

}  // namespace
}  // namespace hystloop
