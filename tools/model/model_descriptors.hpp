#pragma once
// What the registry needs to know of each model, as types: the settings struct the parameter
// table writes into, how it becomes the model's parameter struct, and the forward and inverse
// classes (Inverse = void when there is none). The tables live in model_tables_*.cpp.

#include <cstddef>
#include <span>
#include <string_view>
#include <vector>

#include "models/banning_stage.hpp"
#include "models/katalenic.hpp"
#include "models/linear.hpp"
#include "models/mem.hpp"
#include "models/prandtl_ishlinskii.hpp"
#include "param_table.hpp"

namespace hystloop::model_tool {

struct MemDescriptor {
  using Settings = MemParams;
  using Params = MemParams;
  using Forward = MemModel;
  using Inverse = MemInverse;
  static constexpr std::string_view name = "mem";
  static constexpr std::string_view summary =
      "memory-element (Ramberg-Osgood) hysteresis, Strijbosch-Tiels-Oomen; exact inverse (Theorem 10)";
  static constexpr std::string_view notes = "";
  static std::span<const ParamSpec<Settings>> table();
  static Params build(const Settings& s) { return s; }
};

// PI is given either by its operators (weights, optionally thresholds) or by a size and range,
// with weights then matched to the default MEM (pi_params_from_mem): the project's PI baseline.
struct PiSettings {
  std::size_t n = 15;  // operators
  bool n_given = false;
  double u_max = 250.0;            // [V] input amplitude the even thresholds span: r_i = i u_max / n
  std::vector<double> thresholds;  // [V]
  std::vector<double> weights;     // [m/V]
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
      "without weights: n plays at r_i = i*u_max/n with weights matched to the default MEM; "
      "weights alone: even thresholds over u_max; thresholds need weights";
  static std::span<const ParamSpec<Settings>> table();
  static Params build(const Settings& s);  // throws ParameterError naming the field
};

struct LinearDescriptor {
  using Settings = LinearParams;
  using Params = LinearParams;
  using Forward = LinearModel;
  using Inverse = LinearInverse;
  static constexpr std::string_view name = "linear";
  static constexpr std::string_view summary = "linear spring y = gain*u + offset (no hysteresis)";
  static constexpr std::string_view notes = "";
  static std::span<const ParamSpec<Settings>> table();
  static Params build(const Settings& s) { return s; }
};

struct KatalenicDescriptor {
  using Settings = KatalenicParams;
  using Params = KatalenicParams;
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
  static Params build(const Settings& s) { return s; }
};

struct BanningDescriptor {
  using Settings = BanningStageParams;
  using Params = BanningStageParams;
  using Forward = BanningStage;
  using Inverse = void;
  static constexpr std::string_view name = "banning";
  static constexpr std::string_view summary =
      "Banning et al. 2001 stage: Coleman-Hodgdon hysteresis + second-order mechanics (Tables 1, 2)";
  static constexpr std::string_view notes =
      "dynamic: u is held from the previous row's t to this row's t (t must increase); "
      "forward only (no inverse)";
  static std::span<const ParamSpec<Settings>> table();
  static Params build(const Settings& s) { return s; }
};

}  // namespace hystloop::model_tool
