#include "core/config.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>
#include <vector>

#include "support/refusal.hpp"

namespace hystloop {
namespace {

// Runs `f`, expects a ConfigError, returns its message.
template <class F>
std::string error_of(F&& f) {
  if (const std::optional<ConfigError> e = testing::thrown<ConfigError>(f)) return e->what();
  ADD_FAILURE() << "expected ConfigError";
  return {};
}

const char* kBridge = R"(
bridge:
  u_max_V: 120
  noise_rms_m: 2.0e-9
  simulated: true
  name: bench-rig
  watchdog_ms: 2
  gains: [1.5, 2, 3e-3]
stage:
  model: banning
)";

TEST(Config, ReadsTypedValuesByDottedPath) {
  const Config cfg = Config::from_string(kBridge, "bridge.yaml");
  EXPECT_EQ(cfg.get<double>("bridge.u_max_V", 250.0), 120.0);
  EXPECT_EQ(cfg.get<double>("bridge.noise_rms_m", 0.0), 2.0e-9);
  EXPECT_EQ(cfg.get<bool>("bridge.simulated", false), true);
  EXPECT_EQ(cfg.get<std::string>("bridge.name", "x"), "bench-rig");
  EXPECT_EQ(cfg.get<int>("bridge.watchdog_ms", 0), 2);
  EXPECT_EQ(cfg.get<std::int64_t>("bridge.watchdog_ms"), 2);
  EXPECT_EQ(cfg.get<std::vector<double>>("bridge.gains"), (std::vector<double>{1.5, 2.0, 3e-3}));
  EXPECT_EQ(cfg.get<std::string>("stage.model"), "banning");
  EXPECT_TRUE(cfg.has("bridge.u_max_V"));
  EXPECT_FALSE(cfg.has("bridge.nothing"));
}

TEST(Config, AbsentKeysGiveTheDefault) {
  const Config cfg = Config::from_string(kBridge, "bridge.yaml");
  EXPECT_EQ(cfg.get<double>("bridge.slew_V_per_s", 1e6), 1e6);
  EXPECT_EQ(cfg.get<double>("compensator.gain", 0.5), 0.5);
  EXPECT_EQ(cfg.get("stage.mass_kg", 3), 3);
  EXPECT_EQ(Config().get<std::string>("a.b", "d"), "d");
}

TEST(Config, RefusedValuesNameFileFieldAndReason) {
  const Config cfg = Config::from_string("bridge:\n  u_max_V: -5\n  k: abc\n  n: 3.5\n  e:\n", "bridge.yaml");
  EXPECT_EQ(error_of([&] { (void)cfg.get_positive("bridge.u_max_V", 250.0); }),
            "bridge.yaml: bridge.u_max_V: must be > 0 (got -5)");
  EXPECT_EQ(error_of([&] { (void)cfg.get<double>("bridge.k", 1.0); }),
            "bridge.yaml: bridge.k: expected a number, got 'abc'");
  EXPECT_EQ(error_of([&] { (void)cfg.get<int>("bridge.n", 1); }),
            "bridge.yaml: bridge.n: expected an integer, got '3.5'");
  EXPECT_EQ(error_of([&] { (void)cfg.get<bool>("bridge.k", true); }),
            "bridge.yaml: bridge.k: expected true or false, got 'abc'");
  EXPECT_EQ(error_of([&] { (void)cfg.get<double>("bridge.e", 1.0); }),
            "bridge.yaml: bridge.e: expected a number, got no value");
  EXPECT_EQ(error_of([&] { (void)cfg.get<double>("bridge", 1.0); }),
            "bridge.yaml: bridge: expected a number, got a map");
  EXPECT_EQ(error_of([&] { (void)cfg.get<double>("bridge.missing"); }),
            "bridge.yaml: bridge.missing: required but missing");
  EXPECT_EQ(error_of([&] { (void)cfg.get<double>("bridge.u_max_V.x", 1.0); }),
            "bridge.yaml: bridge.u_max_V: expected a map, got '-5'");
  EXPECT_EQ(error_of([&] { (void)cfg.get<double>("bridge..x", 1.0); }),
            "bridge.yaml: bridge..x: malformed key (empty part between dots)");
}

TEST(Config, ErrorIsAParameterErrorWithTheField) {
  const Config cfg = Config::from_string("a: {b: -1}", "f.yaml");
  try {
    (void)cfg.get_non_negative("a.b", 0.0);
    FAIL();
  } catch (const ParameterError& e) {  // services may catch the base class
    EXPECT_EQ(e.field(), "a.b");
    EXPECT_EQ(std::string(e.what()), "f.yaml: a.b: must be >= 0 (got -1)");
  }
}

TEST(Config, RangeChecks) {
  const Config cfg = Config::from_string("bridge: {noise_rms_m: 2e-6, n: 40}", "bridge.yaml");
  EXPECT_EQ(error_of([&] { (void)cfg.get_in_range("bridge.noise_rms_m", 1e-9, 0, 1e-6); }),
            "bridge.yaml: bridge.noise_rms_m: must be in [0, 1e-06] (got 2e-06)");
  EXPECT_EQ(cfg.get_in_range("bridge.other_m", 1e-9, 0, 1e-6), 1e-9);
  EXPECT_EQ(cfg.get_int_in_range("bridge.n", 1, 0, 99), 40);
  EXPECT_EQ(error_of([&] { (void)cfg.get_int_in_range("bridge.n", 1, 0, 10); }),
            "bridge.yaml: bridge.n: must be in [0, 10] (got 40)");
  // A default outside the range is refused too (a programming error, caught at start-up).
  EXPECT_THROW((void)cfg.get_in_range("bridge.absent", 5.0, 0, 1), ConfigError);
}

TEST(Config, NonFiniteNumbersAreRefused) {
  const Config cfg = Config::from_string("a: .inf\nb: .nan\n", "x.yaml");
  EXPECT_EQ(error_of([&] { (void)cfg.get<double>("a", 0.0); }), "x.yaml: a: must be a finite number (got .inf)");
  EXPECT_THROW((void)cfg.get<double>("b", 0.0), ConfigError);
}

TEST(Config, UnknownKeysAreListedWithSuggestions) {
  const Config cfg = Config::from_string("bridge: {u_maxV: 1, noise_rms_m: 1e-9}\n", "bridge.yaml");
  EXPECT_EQ(error_of([&] {
              cfg.check_no_unknown_keys({"bridge.u_max_V", "bridge.noise_rms_m"});
            }),
            "bridge.yaml: bridge.u_maxV: unknown key; did you mean 'bridge.u_max_V'?");

  const Config two = Config::from_string("bridge: {u_maxV: 1, colour: red}\ncompensater: {gain: 1}\n", "b.yaml");
  EXPECT_EQ(error_of([&] {
              two.check_no_unknown_keys({"bridge.u_max_V", "compensator.gain"});
            }),
            "b.yaml: bridge.colour, bridge.u_maxV, compensater.gain: unknown keys; did you mean "
            "'bridge.u_max_V' for 'bridge.u_maxV', 'compensator.gain' for 'compensater.gain'?");

  // The same name in another section is suggested too.
  const Config moved = Config::from_string("compensator: {watchdog_ms: 2}\n", "c.yaml");
  EXPECT_EQ(error_of([&] { moved.check_no_unknown_keys({"bridge.watchdog_ms"}); }),
            "c.yaml: compensator.watchdog_ms: unknown key; did you mean 'bridge.watchdog_ms'?");
}

TEST(Config, KnownKeysWildcardsAndEmptySectionsPass) {
  const Config cfg = Config::from_string(
      "bridge: {u_max_V: 1, points: [{t: 0, y: 1}]}\nlogger: {dir: /tmp, rotate: {mb: 5}}\nstage:\n", "x.yaml");
  EXPECT_NO_THROW(cfg.check_no_unknown_keys({"bridge.u_max_V", "bridge.points", "logger.*", "stage.model"}));
  EXPECT_EQ(cfg.keys(),
            (std::vector<std::string>{"bridge.points", "bridge.u_max_V", "logger.dir", "logger.rotate.mb", "stage"}));
  EXPECT_THROW(cfg.check_no_unknown_keys({"bridge.u_max_V", "bridge.points", "logger.dir"}), ConfigError);
}

TEST(Config, OverridesMergeOverTheFile) {
  Config cfg = Config::from_string(kBridge, "bridge.yaml");
  cfg.apply_overrides(
      {"bridge.u_max_V=90", "bridge.gains=[4, 5]", "compensator.mode=feedforward", "bridge.name=other"});
  EXPECT_EQ(cfg.get<double>("bridge.u_max_V", 0.0), 90.0);
  EXPECT_EQ(cfg.get<std::vector<double>>("bridge.gains"), (std::vector<double>{4, 5}));
  EXPECT_EQ(cfg.get<std::string>("compensator.mode"), "feedforward");
  EXPECT_EQ(cfg.get<std::string>("bridge.name"), "other");
  EXPECT_EQ(cfg.get<double>("bridge.noise_rms_m", 0.0), 2.0e-9);  // untouched siblings stay
  Config empty;
  empty.apply_override("a.b.c=3");
  EXPECT_EQ(empty.get<int>("a.b.c", 0), 3);
}

TEST(Config, OverriddenValuesAreReportedAsComingFromTheCommandLine) {
  Config cfg = Config::from_string(kBridge, "bridge.yaml");
  cfg.apply_override("bridge.u_max_V=-5");
  EXPECT_EQ(error_of([&] { (void)cfg.get_positive("bridge.u_max_V", 1.0); }),
            "--set: bridge.u_max_V: must be > 0 (got -5)");
  cfg.apply_override("bridge.typo=1");
  EXPECT_EQ(error_of([&] {
              cfg.check_no_unknown_keys({"bridge.u_max_V", "bridge.noise_rms_m", "bridge.simulated", "bridge.name",
                                         "bridge.watchdog_ms", "bridge.gains", "stage.model"});
            }),
            "--set: bridge.typo: unknown key");
}

TEST(Config, ALayeredFileMergesMapsKeyByKeyAndReplacesValuesAndListsWhole) {
  Config cfg = Config::from_string(kBridge, "bridge.yaml");
  cfg.layer(Config::from_string("bridge: {u_max_V: 90, gains: [4]}\nstage: {delay_s: 1.5e-4}\nlearning: {gain: 0.3}\n",
                                "scan.yaml"));
  EXPECT_EQ(cfg.get<double>("bridge.u_max_V"), 90.0);
  EXPECT_EQ(cfg.get<std::vector<double>>("bridge.gains"), (std::vector<double>{4}));  // not [4, 2, 3e-3]
  EXPECT_EQ(cfg.get<double>("bridge.noise_rms_m"), 2.0e-9);                           // a sibling stays
  EXPECT_EQ(cfg.get<std::string>("stage.model"), "banning");
  EXPECT_EQ(cfg.get<double>("stage.delay_s"), 1.5e-4);
  EXPECT_EQ(cfg.get<double>("learning.gain"), 0.3);  // a section only the layer has
  // A map over a value replaces it, as a value over a map does.
  cfg.layer(Config::from_string("bridge: {name: {first: a}}\nstage: 3\n", "more.yaml"));
  EXPECT_EQ(cfg.get<std::string>("bridge.name.first"), "a");
  EXPECT_EQ(cfg.get<int>("stage"), 3);
}

TEST(Config, ARefusedValueNamesTheFileThatGaveIt) {
  Config cfg = Config::from_string(kBridge, "bridge.yaml");
  cfg.layer(Config::from_string("bridge: {u_max_V: -5, typo: 1}\n", "scan.yaml"));
  EXPECT_EQ(error_of([&] { (void)cfg.get_positive("bridge.u_max_V", 1.0); }),
            "scan.yaml: bridge.u_max_V: must be > 0 (got -5)");
  // A key the layer left alone is still the base file's.
  EXPECT_EQ(error_of([&] {
              (void)cfg.get_in_range("bridge.watchdog_ms", 5.0, 5.0, 10.0);
            }).rfind("bridge.yaml: bridge.watchdog_ms: ", 0),
            0u);
  EXPECT_EQ(error_of([&] {
              cfg.check_no_unknown_keys({"bridge.u_max_V", "bridge.noise_rms_m", "bridge.simulated", "bridge.name",
                                         "bridge.watchdog_ms", "bridge.gains", "stage.model"});
            }),
            "scan.yaml: bridge.typo: unknown key");
  cfg.apply_override("bridge.u_max_V=-6");  // the command line last, over every file
  EXPECT_EQ(error_of([&] { (void)cfg.get_positive("bridge.u_max_V", 1.0); }),
            "--set: bridge.u_max_V: must be > 0 (got -6)");
}

TEST(Config, MalformedOverridesAreRefused) {
  Config cfg = Config::from_string(kBridge, "bridge.yaml");
  EXPECT_EQ(error_of([&] { cfg.apply_override("bridge.u_max_V"); }), "--set: expected key=value, got 'bridge.u_max_V'");
  EXPECT_EQ(error_of([&] { cfg.apply_override("=3"); }), "--set: expected key=value, got '=3'");
  EXPECT_EQ(error_of([&] { cfg.apply_override("a..b=3"); }), "--set: a..b: malformed key (empty part between dots)");
  EXPECT_EQ(error_of([&] { cfg.apply_override("bridge.u_max_V.x=3"); }),
            "--set: bridge.u_max_V: cannot set a key inside it: it is '120', not a map");
  EXPECT_THROW(cfg.apply_override("a=[1, 2"), ConfigError);
}

TEST(Config, CopiesAreIndependent) {
  const Config original = Config::from_string(kBridge, "bridge.yaml");
  Config copy = original;
  copy.apply_override("bridge.u_max_V=1");
  EXPECT_EQ(original.get<double>("bridge.u_max_V", 0.0), 120.0);
  EXPECT_EQ(copy.get<double>("bridge.u_max_V", 0.0), 1.0);
  Config assigned;
  assigned = original;
  assigned.apply_override("stage.model=ro");
  EXPECT_EQ(original.get<std::string>("stage.model"), "banning");
}

TEST(Config, LoadsFilesAndReportsSyntaxErrorsWithALine) {
  const auto dir = std::filesystem::temp_directory_path();
  const auto good = dir / ("hystloop_cfg_" + std::to_string(::getpid()) + "_good.yaml");
  const auto bad = dir / ("hystloop_cfg_" + std::to_string(::getpid()) + "_bad.yaml");
  const auto empty = dir / ("hystloop_cfg_" + std::to_string(::getpid()) + "_empty.yaml");
  std::ofstream(good) << kBridge;
  std::ofstream(bad) << "bridge:\n  u_max_V: [1, 2\n";
  std::ofstream(empty) << "# nothing yet\n";

  const Config cfg = Config::load_file(good);
  EXPECT_EQ(cfg.source(), good.string());
  EXPECT_EQ(cfg.get<double>("bridge.u_max_V", 0.0), 120.0);
  EXPECT_EQ(error_of([&] { (void)Config::load_file(dir / "hystloop_no_such.yaml"); }),
            (dir / "hystloop_no_such.yaml").string() + ": cannot open file");
  const std::string syntax = error_of([&] { (void)Config::load_file(bad); });
  EXPECT_EQ(syntax.rfind(bad.string() + ": line ", 0), 0u) << syntax;
  EXPECT_TRUE(Config::load_file(empty).keys().empty());
  EXPECT_EQ(error_of([] { (void)Config::from_string("- 1\n- 2\n", "list.yaml"); }),
            "list.yaml: the top level must be a map of keys, got a list");
  for (const auto& p : {good, bad, empty}) std::filesystem::remove(p);
}

// yaml-cpp keeps the first of two equal keys and answers with it: the second `u_max_V` of a file
// edited in a hurry was silently ignored. Refused, naming the file, the key and both lines.
TEST(Config, DuplicateKeysAreRefusedWithTheFileLineAndKey) {
  EXPECT_EQ(error_of([] {
              (void)Config::from_string("bridge:\n  u_max_V: 120\n  noise_rms_m: 1e-9\n  u_max_V: 250\n",
                                        "bridge.yaml");
            }),
            "bridge.yaml: bridge.u_max_V: duplicate key at line 4 (first at line 2): remove one of them");
  EXPECT_EQ(error_of([] { (void)Config::from_string("a: 1\nb: {c: 2}\na: 3\n", "top.yaml"); }),
            "top.yaml: a: duplicate key at line 3 (first at line 1): remove one of them");
  // Flow maps, maps inside lists, and --set values too.
  EXPECT_NE(error_of([] { (void)Config::from_string("s: [{k: 1, k: 2}]\n", "l.yaml"); }).find("s[0].k: duplicate key"),
            std::string::npos);
  Config cfg;
  EXPECT_NE(
      error_of([&] { cfg.apply_override("bridge.gains={a: 1, a: 2}"); }).find("--set: bridge.gains.a: duplicate key"),
      std::string::npos);
  // The same key in different sections is not a duplicate.
  const Config ok = Config::from_string("a: {x: 1}\nb: {x: 2}\n", "ok.yaml");
  EXPECT_EQ(ok.get<int>("b.x", 0), 2);

  const auto file =
      std::filesystem::temp_directory_path() / ("hystloop_cfg_" + std::to_string(::getpid()) + "_dup.yaml");
  std::ofstream(file) << kBridge << "bridge:\n  u_max_V: 5\n";
  EXPECT_EQ(error_of([&] { (void)Config::load_file(file); }),
            file.string() + ": bridge: duplicate key at line 11 (first at line 2): remove one of them");
  std::filesystem::remove(file);
}

TEST(Config, DumpRoundTrips) {
  Config cfg = Config::from_string(kBridge, "bridge.yaml");
  cfg.apply_override("bridge.u_max_V=77");
  const Config again = Config::from_string(cfg.dump(), "dump");
  EXPECT_EQ(again.get<double>("bridge.u_max_V", 0.0), 77.0);
  EXPECT_EQ(again.keys(), cfg.keys());
}

TEST(Config, ReadsListsOfRowsAndListsOfRecords) {
  Config cfg = Config::from_string(
      "stage:\n"
      "  poles_hz: [[-50, 1000], [-2000, 0]]\n"
      "  modes: [{frequency_hz: 780, damping_ratio: 0.03}, {frequency_hz: 2400, damping_ratio: 0.02, weight: 0.08}]\n",
      "stage.yaml");
  const auto rows = cfg.get_rows("stage.poles_hz", 2);
  ASSERT_EQ(rows.size(), 2U);
  EXPECT_EQ(rows[0], (std::vector<double>{-50.0, 1000.0}));
  EXPECT_EQ(rows[1], (std::vector<double>{-2000.0, 0.0}));
  EXPECT_TRUE(cfg.get_rows("stage.zeros_hz", 2).empty());  // absent
  const auto modes = cfg.get_records("stage.modes", {"frequency_hz", "damping_ratio", "weight"});
  ASSERT_EQ(modes.size(), 2U);
  EXPECT_EQ(modes[0][0], 780.0);
  EXPECT_TRUE(std::isnan(modes[0][2]));  // not given: the caller's default
  EXPECT_EQ(modes[1][2], 0.08);
  EXPECT_EQ(error_of([&] { cfg.get_rows("stage.poles_hz", 3); }),
            "stage.yaml: stage.poles_hz[0]: expected 3 numbers, got 2");
  EXPECT_EQ(error_of([&] { cfg.get_rows("stage.modes", 2); }),
            "stage.yaml: stage.modes[0]: expected a list, got a map");
  EXPECT_EQ(error_of([&] {
              cfg.get_records("stage.modes", {"frequency_hz", "damping"});
            }),
            "stage.yaml: stage.modes[0].damping_ratio: unknown key (expected frequency_hz, damping)");
  EXPECT_EQ(error_of([&] {
              cfg.get_records("stage.poles_hz", {"re", "im"});
            }),
            "stage.yaml: stage.poles_hz[0]: expected a map of re, im, got a list");
  cfg.apply_override("stage.poles_hz=[[-50, abc]]");
  EXPECT_EQ(error_of([&] { cfg.get_rows("stage.poles_hz", 2); }),
            "--set: stage.poles_hz[0][1]: expected a number, got 'abc'");
}

}  // namespace
}  // namespace hystloop
