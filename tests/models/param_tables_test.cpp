// The models' parameter tables (models/model_descriptors.hpp) that drive hystloop-identify's YAML,
// hystloop-model's --param and the compensator's model sections: every row is written and read
// back to the same value, names are unique, older spellings are accepted and unknown ones are
// refused naming them.
#include <gtest/gtest.h>

#include <set>
#include <string>
#include <vector>

#include "core/config.hpp"
#include "models/model_descriptors.hpp"
#include "models/param_config.hpp"
#include "models/param_text.hpp"

namespace hystloop {
namespace {

// A value for row `index` that no default has and that needs all 17 digits to read back.
template <class S>
ParsedValue distinct_value(const ParamSpec<S>& row, std::size_t index, std::size_t list_size) {
  ParsedValue v;
  v.number = 0.1234567890123456789 + static_cast<double>(index);
  v.count = list_size;
  for (std::size_t i = 0; i < list_size; ++i) v.list.push_back(v.number * static_cast<double>(i + 1) / 3.0);
  const std::string_view choices = row.choices;
  v.choice = std::string(choices.substr(choices.rfind('|') + 1));  // the last one: not the default
  return v;
}

// The section as written, read back through a Config (as the compensator reads it) onto S{}.
template <class D>
typename D::Settings read_back(const std::string& yaml) {
  const Config config = Config::from_string(yaml, "written.yaml");
  typename D::Settings back{};
  apply(D::table(), D::name, config_section(config, D::name, D::table()), back);
  return back;
}

// For each base set and each row that applies to it: the row set to a distinct value, written,
// read back; the YAML of what was read is the YAML written, and every row was exercised.
template <class D>
void expect_every_row_round_trips(const std::vector<typename D::Settings>& bases, std::size_t list_size) {
  const auto table = D::table();
  std::vector<bool> exercised(table.size(), false);
  for (const auto& base : bases) {
    for (std::size_t i = 0; i < table.size(); ++i) {
      typename D::Settings s = base;
      table[i].set(s, distinct_value(table[i], i, list_size));
      // The row stores into a field of its own: no other row sees the change.
      for (std::size_t j = 0; j < table.size(); ++j) {
        if (j == i) continue;
        EXPECT_EQ(table[j].show(s), table[j].show(base)) << D::name << "." << table[i].name;
      }
      if (table[i].applies != nullptr && !table[i].applies(s)) continue;
      exercised[i] = true;
      const std::string written = yaml_section(D::name, table, s);
      if (table[i].kind != ValueKind::list) {
        EXPECT_NE(written.find(": " + table[i].show(s)), std::string::npos) << written;
      }
      const typename D::Settings back = read_back<D>(written);
      EXPECT_EQ(table[i].show(back), table[i].show(s)) << D::name << "." << table[i].name << "\n" << written;
      EXPECT_EQ(yaml_section(D::name, table, back), written) << D::name << "." << table[i].name;
    }
  }
  for (std::size_t i = 0; i < table.size(); ++i) EXPECT_TRUE(exercised[i]) << D::name << "." << table[i].name;
}

TEST(ParamTables, EveryRowOfEveryModelRoundTripsThroughYaml) {
  expect_every_row_round_trips<MemDescriptor>({MemParams{}}, 0);
  expect_every_row_round_trips<LinearDescriptor>({LinearParams{}}, 0);
  expect_every_row_round_trips<BanningDescriptor>({BanningStageParams{}}, 0);
  // PI: by size and range (range_V written), and by its plays (thresholds and weights written).
  PiSettings plays;
  plays.count = 3;
  plays.count_given = true;
  plays.thresholds = {0.0, 80.0, 160.0};
  plays.weights = {5e-9, 1e-9, 5e-10};
  expect_every_row_round_trips<PiDescriptor>({PiSettings{}, plays}, 3);
  // Katalenic: each shaping kind on both sides, so each shaping field is written once at least.
  std::vector<KatalenicParams> shapes(3);
  shapes[1].input_shaping = shapes[1].output_shaping = ShapingFunction::make_polynomial({0.0, 1.0, 0.0, 1e-6}, -3, 3);
  shapes[2].input_shaping = shapes[2].output_shaping = ShapingFunction::make_tanh(2.0, 3.0, 0.5);
  expect_every_row_round_trips<KatalenicDescriptor>(shapes, 4);
}

template <class D>
std::string to_yaml_text(const typename D::Params& p) {
  return yaml_section(D::name, D::table(), D::settings_of(p));
}

// The parameter struct -> YAML -> table -> parameter struct, for sets of every kind.
template <class D>
void expect_params_round_trip(const typename D::Params& p) {
  const std::string written = yaml_section(D::name, D::table(), D::settings_of(p));
  const typename D::Params back = D::build(read_back<D>(written));
  EXPECT_EQ(yaml_section(D::name, D::table(), D::settings_of(back)), written);
}

TEST(ParamTables, ParameterSetsRoundTripThroughYaml) {
  const MemParams mem{4.123456789012345e-9, 2.1e-12, 1.15};
  expect_params_round_trip<MemDescriptor>(mem);
  const MemParams mem_back = read_back<MemDescriptor>(to_yaml_text<MemDescriptor>(mem));
  EXPECT_EQ(mem_back.c1, mem.c1);
  EXPECT_EQ(mem_back.c2, mem.c2);
  EXPECT_EQ(mem_back.c3, mem.c3);
  expect_params_round_trip<LinearDescriptor>({6.3e-9, 1e-9});
  const PiParams pi = pi_params_from_mem(MemParams::paper_like(), 15, 250.0);
  expect_params_round_trip<PiDescriptor>(pi);
  const std::string written = yaml_section(PiDescriptor::name, PiDescriptor::table(), PiDescriptor::settings_of(pi));
  const PiParams back = PiDescriptor::build(read_back<PiDescriptor>(written));
  ASSERT_EQ(back.count, pi.count);
  for (std::size_t i = 0; i < pi.count; ++i) {
    EXPECT_EQ(back.thresholds[i], pi.thresholds[i]) << i;
    EXPECT_EQ(back.weights[i], pi.weights[i]) << i;
  }
  KatalenicParams k;
  k.output_shaping = ShapingFunction::make_polynomial({0.0, 3.8e-9, 0.0, 1e-16}, -300, 300);
  expect_params_round_trip<KatalenicDescriptor>(k);
}

TEST(ParamTables, YamlSaysOnlyWhatTheSetUses) {
  // A linear shaping writes gain and offset, not a tanh's amplitude; explicit plays no range.
  const std::string kat = yaml_section(KatalenicDescriptor::name, KatalenicDescriptor::table(), KatalenicParams{});
  EXPECT_NE(kat.find("  input_shaping:\n    kind: linear\n    gain: 1  # [x/V]\n"), std::string::npos) << kat;
  EXPECT_EQ(kat.find("amplitude"), std::string::npos) << kat;
  const PiParams pi = PiParams::with_even_thresholds(3, 120.0);
  const std::string plays = yaml_section(PiDescriptor::name, PiDescriptor::table(), PiDescriptor::settings_of(pi));
  EXPECT_EQ(plays.find("range_V"), std::string::npos) << plays;
  EXPECT_NE(plays.find("  thresholds: [0, 40, 80]  # [V]\n"), std::string::npos) << plays;
}

template <class D>
void expect_unique_names() {
  std::set<std::string> names;
  for (const auto& row : D::table()) {
    EXPECT_TRUE(names.insert(std::string(row.name)).second) << D::name << "." << row.name;
    if (!row.alias.empty()) {
      EXPECT_TRUE(names.insert(std::string(row.alias)).second) << D::name << "." << row.alias;
    }
    EXPECT_FALSE(row.unit.empty()) << D::name << "." << row.name;
    EXPECT_FALSE(row.description.empty()) << D::name << "." << row.name;
  }
}

TEST(ParamTables, NamesAndAliasesAreUniqueAndEveryRowHasUnitAndHelp) {
  expect_unique_names<MemDescriptor>();
  expect_unique_names<PiDescriptor>();
  expect_unique_names<LinearDescriptor>();
  expect_unique_names<KatalenicDescriptor>();
  expect_unique_names<BanningDescriptor>();
}

TEST(ParamTables, PiTakesBothSpellingsOfItsSizeAndRange) {
  PiSettings by_alias;
  apply(PiDescriptor::table(), "pi", {{"n", "7", "n=7"}, {"u_max", "200", "u_max=200"}}, by_alias);
  PiSettings by_name;
  apply(PiDescriptor::table(), "pi", {{"count", "7", "count=7"}, {"range_V", "200", "range_V=200"}}, by_name);
  EXPECT_EQ(by_alias.count, 7u);
  EXPECT_EQ(by_alias.range_V, 200.0);
  const PiParams a = PiDescriptor::build(by_alias);
  const PiParams b = PiDescriptor::build(by_name);
  const PiParams expected = pi_params_from_mem(MemParams::paper_like(), 7, 200.0);
  for (std::size_t i = 0; i < 7; ++i) {
    EXPECT_EQ(a.weights[i], expected.weights[i]) << i;
    EXPECT_EQ(b.weights[i], expected.weights[i]) << i;
  }
}

TEST(ParamTables, AnUnknownNameIsRefusedNamingIt) {
  MemParams m;
  try {
    apply(MemDescriptor::table(), "mem", {{"c4", "1e-9", "mem.c4"}}, m);
    FAIL() << "c4 accepted";
  } catch (const AssignmentError& e) {
    EXPECT_EQ(e.field(), "c4");
    EXPECT_NE(std::string(e.what()).find("unknown parameter 'c4' of model mem; did you mean 'c1'?"), std::string::npos)
        << e.what();
  }
}

TEST(ParamTables, SummaryLineNamesTheMarkedRows) {
  EXPECT_EQ(MemDescriptor::summary_of({5.3e-9, 2.1000000000000001e-12, 1.1499999999999999}),
            "c1 5.3e-09 m/V, c2 2.1e-12 m/V^(1+c3), c3 1.15");
  EXPECT_EQ(PiDescriptor::summary_of(PiParams::with_even_thresholds(3, 240.0)), "3 plays up to 160 V");
  EXPECT_EQ(LinearDescriptor::summary_of({6.34e-9, 0.0}), "gain 6.34e-09 m/V, offset 0 m");
}

}  // namespace
}  // namespace hystloop
