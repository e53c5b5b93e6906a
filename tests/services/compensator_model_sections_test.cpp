// The compensator's model sections (mem, pi, linear, katalenic) are read through the models'
// parameter tables (models/model_descriptors.hpp): every key of a table is accepted, a snippet
// the tables write loads unchanged, older spellings still load, and a refusal names the key.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>

#include "compensator/compensator_service.hpp"
#include "compensator/compensator_settings.hpp"
#include "models/model_descriptors.hpp"

namespace hystloop {
namespace {

const std::string kConfig = std::string(HYSTLOOP_SOURCE_DIR) + "/deploy/config/compensator.yaml";

std::string refusal(const std::string& yaml) {
  try {
    load_compensator_settings(Config::from_string(yaml, "compensator.yaml"));
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "accepted";
}

// The section as its table writes it: equal text is equal values (shortest round-trip numbers).
template <class D>
std::string section(const typename D::Params& p) {
  return yaml_section(D::name, D::table(), D::settings_of(p));
}

std::string sections(const CompensatorSettings& s) {
  const CompensatorConfig& c = s.control;
  return section<MemDescriptor>(c.models.mem) + section<PiDescriptor>(c.models.pi) +
         section<LinearDescriptor>(c.models.linear) + section<KatalenicDescriptor>(c.models.katalenic);
}

// Each key and alias of D's table, set to the value the deployed config already has: accepted,
// listed among the compensator's keys, and the sections read are the same.
template <class D>
void expect_every_key_accepted(const typename D::Params& deployed, const std::string& expected) {
  const auto settings = D::settings_of(deployed);
  const std::vector<std::string>& known = compensator_config_keys();
  for (const auto& row : D::table()) {
    std::string value = row.show(settings);
    if (row.kind == ValueKind::list) value.insert(0, 1, '[').push_back(']');
    for (const std::string_view name : {row.name, row.alias}) {
      if (name.empty()) continue;
      const std::string key = std::string(D::name).append(1, '.').append(name);
      EXPECT_NE(std::find(known.begin(), known.end(), key), known.end()) << key;
      Config config = Config::load_file(kConfig);
      config.apply_override(std::string(key).append(1, '=').append(value));
      try {
        EXPECT_EQ(sections(load_compensator_settings(config)), expected) << key << "=" << value;
      } catch (const ConfigError& e) {
        ADD_FAILURE() << key << "=" << value << " refused: " << e.what();
      }
    }
  }
}

TEST(CompensatorModelSections, EveryKeyOfEveryTableIsAccepted) {
  const CompensatorSettings s = load_compensator_settings(Config::load_file(kConfig));
  const std::string expected = sections(s);
  expect_every_key_accepted<MemDescriptor>(s.control.models.mem, expected);
  expect_every_key_accepted<PiDescriptor>(s.control.models.pi, expected);
  expect_every_key_accepted<LinearDescriptor>(s.control.models.linear, expected);
  expect_every_key_accepted<KatalenicDescriptor>(s.control.models.katalenic, expected);
}

TEST(CompensatorModelSections, AnUnknownKeyIsRefusedNamingIt) {
  const std::string mem = refusal("mem: {c1: 5e-9, c4: 1e-9}");
  EXPECT_NE(mem.find("mem.c4"), std::string::npos) << mem;
  EXPECT_NE(mem.find("did you mean 'mem.c1'"), std::string::npos) << mem;
  // Under a shaping function too (these were let through unread before the tables).
  const std::string kat = refusal("katalenic: {input_shaping: {kind: linear, gian: 1.0}}");
  EXPECT_NE(kat.find("katalenic.input_shaping.gian"), std::string::npos) << kat;
}

TEST(CompensatorModelSections, ARefusedValueNamesTheKey) {
  const std::string text = refusal("mem: {c1: 5e-9x}");
  EXPECT_NE(text.find("compensator.yaml: mem.c1: expected a number, got '5e-9x'"), std::string::npos) << text;
  const std::string negative = refusal("mem: {c3: -1}");
  EXPECT_NE(negative.find("compensator.yaml: mem.c3: must be > 0 (got -1)"), std::string::npos) << negative;
  const std::string alone = refusal("pi: {thresholds: [0, 10]}");
  EXPECT_NE(alone.find("pi.thresholds: given without weights"), std::string::npos) << alone;
  const std::string fewer = refusal("pi: {thresholds: [0, 10], weights: [1e-9]}");
  EXPECT_NE(fewer.find("pi.weights: has 1 entries but thresholds has 2"), std::string::npos) << fewer;
  const std::string count = refusal("pi: {count: 3, thresholds: [0, 10], weights: [5e-9, 1e-9]}");
  EXPECT_NE(count.find("pi.count: is 3 but weights has 2 entries"), std::string::npos) << count;
  const std::string coefficients =
      refusal("katalenic: {output_shaping: {kind: polynomial, coefficients: [1, 2, 3, 4, 5, 6, 7, 8, 9]}}");
  EXPECT_NE(coefficients.find("katalenic.output_shaping.coefficients: at most 8"), std::string::npos) << coefficients;
}

TEST(CompensatorModelSections, PiBySizeAndRangeIsMatchedToTheConfiguredMemUnderEitherSpelling) {
  const MemParams mem{4e-9, 1e-12, 1.1};
  const PiParams expected = pi_params_from_mem(mem, 7, 200.0);
  for (const char* pi : {"pi: {count: 7, range_V: 200}", "pi: {n: 7, u_max: 200}"}) {
    const CompensatorSettings s = load_compensator_settings(
        Config::from_string(std::string("mem: {c1: 4e-9, c2: 1e-12, c3: 1.1}\n") + pi, "compensator.yaml"));
    ASSERT_EQ(s.control.models.pi.count, 7u) << pi;
    for (std::size_t i = 0; i < 7; ++i) {
      EXPECT_EQ(s.control.models.pi.thresholds[i], expected.thresholds[i]) << pi << " " << i;
      EXPECT_EQ(s.control.models.pi.weights[i], expected.weights[i]) << pi << " " << i;
    }
  }
  // Without a pi section: the 15-play baseline over +-250 V, as before the tables.
  const CompensatorSettings none = load_compensator_settings(Config::from_string("{}", "compensator.yaml"));
  EXPECT_EQ(section<PiDescriptor>(none.control.models.pi),
            section<PiDescriptor>(pi_params_from_mem(none.control.models.mem, 15, 250.0)));
}

TEST(CompensatorModelSections, ASnippetTheTablesWriteLoadsUnchanged) {
  PiParams pi = PiParams::with_even_thresholds(3, 240.0);
  pi.weights[0] = 5.123456789012345e-9;
  pi.weights[1] = 1e-9;
  pi.weights[2] = 5e-10;
  KatalenicParams kat;
  kat.k1 = 35.0;
  kat.output_shaping = ShapingFunction::make_polynomial({0.0, 3.8e-9, 0.0, 1e-16}, -300, 300);
  const MemParams mem{5.3e-9, 2.1e-12, 1.15};
  const std::filesystem::path path = std::filesystem::temp_directory_path() / "hystloop_model_sections_test.yaml";
  std::ofstream(path) << section<MemDescriptor>(mem) << section<PiDescriptor>(pi) << section<KatalenicDescriptor>(kat);
  Config config = Config::load_file(kConfig);
  merge_params_file(config, path);
  std::filesystem::remove(path);
  const CompensatorSettings s = load_compensator_settings(config);
  EXPECT_EQ(section<MemDescriptor>(s.control.models.mem), section<MemDescriptor>(mem));
  EXPECT_EQ(section<PiDescriptor>(s.control.models.pi), section<PiDescriptor>(pi));
  EXPECT_EQ(section<KatalenicDescriptor>(s.control.models.katalenic), section<KatalenicDescriptor>(kat));
  // The start-up summary says so, in the words the integration test looks for.
  const std::vector<std::string> lines = describe(s);
  EXPECT_NE(std::find(lines.begin(), lines.end(), "mem: c1 5.3e-09 m/V, c2 2.1e-12 m/V^(1+c3), c3 1.15"), lines.end());
  EXPECT_NE(std::find(lines.begin(), lines.end(), "pi: 3 plays up to 160 V"), lines.end());
}

// A set accepted or swapped in is logged as the start-up summary names its model: one text per
// model, from its table, so a parameter added to a table shows in both.
TEST(CompensatorModelSections, ASetIsLoggedAsTheStartUpSummaryNamesIt) {
  const CompensatorSettings s = load_compensator_settings(Config::load_file(kConfig));
  const std::vector<std::string> lines = describe(s);
  for (int i = 0; i < kModelKindCount; ++i) {
    ModelParamSet set;
    set.kind = static_cast<ModelKind>(i);
    static_cast<ModelParams&>(set) = s.control.models;
    EXPECT_NE(std::find(lines.begin(), lines.end(), describe_model(set)), lines.end()) << describe_model(set);
  }
  ModelParamSet mem;
  mem.mem = MemParams{5.3e-9, 2.1e-12, 1.15};
  EXPECT_EQ(describe_model(mem), "mem: c1 5.3e-09 m/V, c2 2.1e-12 m/V^(1+c3), c3 1.15");
  ModelParamSet pi;
  pi.kind = ModelKind::pi;
  pi.pi = PiParams::with_even_thresholds(3, 240.0);
  EXPECT_EQ(describe_model(pi), "pi: 3 plays up to 160 V");
}

}  // namespace
}  // namespace hystloop
