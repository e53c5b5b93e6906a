#pragma once
// Each model's description, as types: the settings struct its parameter table writes into, how
// that becomes the model's parameter struct and back, a one-line summary of a set, and the
// forward and inverse classes (Inverse = void when there is none). The tables live in
// model_tables*.cpp. hystloop-model's registry, hystloop-identify's YAML (ident/params_yaml)
// and the compensator's model sections all go through these, so a parameter is added to a model
// in its table alone.

#include <cstddef>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "models/banning_stage.hpp"
#include "models/katalenic.hpp"
#include "models/linear.hpp"
#include "models/mem.hpp"
#include "models/prandtl_ishlinskii.hpp"
#include "models/param_table.hpp"
#include "models/param_text.hpp"

namespace hystloop {

// A model whose table stores straight into its parameter struct (all but PI); D is the model's
// descriptor, which declares table().
template <class D, class P>
struct StoresParams {
  using Settings = P;
  using Params = P;
  static constexpr std::string_view notes = "";  // extra help lines
  static Params build(const Settings& s) { return s; }
  static Settings settings_of(const Params& p) { return p; }
  static std::string summary_of(const Params& p) { return summary_line(D::table(), p); }  // the in_summary rows
};

struct MemDescriptor : StoresParams<MemDescriptor, MemParams> {
  using Forward = MemModel;
  using Inverse = MemInverse;
  static constexpr std::string_view name = "mem";
  static constexpr std::string_view summary =
      "memory-element (Ramberg-Osgood) hysteresis, Strijbosch-Tiels-Oomen; exact inverse (Theorem 10)";
  static std::span<const ParamSpec<Settings>> table();
};

// PI is given either by its operators (weights, optionally thresholds) or by a size and range,
// with weights then matched to a MEM (pi_params_from_mem): the project's PI baseline.
struct PiSettings {
  std::size_t count = 15;  // operators
  bool count_given = false;
  double range_V = 250.0;          // [V] input amplitude the even thresholds span: r_i = i range_V / count
  std::vector<double> thresholds;  // [V]
  std::vector<double> weights;     // [m/V]
  // The MEM the baseline's weights match: the default one, or the compensator's configured one.
  MemParams matched_to = MemParams::paper_like();
};

struct PiDescriptor {
  using Settings = PiSettings;
  using Params = PiParams;
  using Forward = PiModel;
  using Inverse = PiInverse;
  static constexpr std::string_view name = "pi";
  static constexpr std::string_view summary =
      "Prandtl-Ishlinskii, play operators (Kuhnen 2003); exact inverse PI operator";
  static constexpr std::string_view notes =
      "without weights: count plays at r_i = i*range_V/count with weights matched to the default MEM; "
      "weights alone: even thresholds over range_V; thresholds need weights";
  static std::span<const ParamSpec<Settings>> table();
  static Params build(const Settings& s);  // throws ParameterError naming the field
  static Settings settings_of(const Params& p);
  static std::string summary_of(const Params& p);  // "15 plays up to 233.3 V"
};

struct LinearDescriptor : StoresParams<LinearDescriptor, LinearParams> {
  using Forward = LinearModel;
  using Inverse = LinearInverse;
  static constexpr std::string_view name = "linear";
  static constexpr std::string_view summary = "linear spring y = gain*u + offset (no hysteresis)";
  static std::span<const ParamSpec<Settings>> table();
};

struct KatalenicDescriptor : StoresParams<KatalenicDescriptor, KatalenicParams> {
  using Forward = KatalenicModel;
  using Inverse = KatalenicInverse;
  static constexpr std::string_view name = "katalenic";
  static constexpr std::string_view summary =
      "Katalenic smooth parametric hysteresis with input/output shaping; exact inverse (Prop. 4.1)";
  static constexpr std::string_view notes =
      "operator units = psi_in(u) (volts with the default input_shaping); "
      "shaping kinds: linear (gain, offset), polynomial (coefficients c0,c1,..., domain_min/max), "
      "tanh (amplitude, scale, offset)";
  static std::span<const ParamSpec<Settings>> table();
};

struct BanningDescriptor : StoresParams<BanningDescriptor, BanningStageParams> {
  using Forward = BanningStage;
  using Inverse = void;
  static constexpr std::string_view name = "banning";
  static constexpr std::string_view summary =
      "Banning et al. 2001 stage: Coleman-Hodgdon hysteresis + second-order mechanics (Tables 1, 2)";
  static constexpr std::string_view notes =
      "dynamic: u is held from the previous row's t to this row's t (t must increase); "
      "forward only (no inverse)";
  static std::span<const ParamSpec<Settings>> table();
};

}  // namespace hystloop
