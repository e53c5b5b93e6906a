#pragma once
// Each model's description, as types: the settings struct its parameter table writes into, how
// that becomes the model's parameter struct and back, a one-line summary of a set, and the
// forward and inverse classes (Inverse = void when there is none). The tables live in
// model_tables*.cpp. hystloop-model's registry, hystloop-identify's YAML (ident/params_yaml)
// and the compensator's model sections all go through these, so a parameter is added to a model
// in its table alone. A model a ModelParamSet holds (OnlineModels, below) also says its kind, its
// member of the set and its fields on the wire (on_wire), so code over every such model (the
// message, validation, plausibility, summaries) names none of them.

#include <cstddef>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "models/banning_stage.hpp"
#include "models/katalenic.hpp"
#include "models/linear.hpp"
#include "models/mem.hpp"
#include "models/model_set.hpp"
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

// on_wire(msg, params, f): f(wire field, parameter field) for every field the model has on the
// wire (model_params_t, whose fields carry the model's prefix), one list for writing, reading and
// clearing a message; M is the message type, so this layer needs no LCM.

struct MemDescriptor : StoresParams<MemDescriptor, MemParams> {
  using Forward = MemModel;
  using Inverse = MemInverse;
  static constexpr std::string_view name = "mem";
  static constexpr std::string_view summary =
      "memory-element (Ramberg-Osgood) hysteresis, Strijbosch-Tiels-Oomen; exact inverse (Theorem 10)";
  static constexpr ModelKind kind = ModelKind::mem;
  static constexpr auto in_set = &ModelParamSet::mem;
  static std::span<const ParamSpec<Settings>> table();
  template <class M, class P, class F>
  static void on_wire(M& m, P& p, F&& f) {
    f(m.mem_c1, p.c1);
    f(m.mem_c2, p.c2);
    f(m.mem_c3, p.c3);
  }
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
  static constexpr ModelKind kind = ModelKind::pi;
  static constexpr auto in_set = &ModelParamSet::pi;
  static std::span<const ParamSpec<Settings>> table();
  // The arrays' first `count` entries are the wire's; reading, count shrinks to the shortest.
  template <class M, class P, class F>
  static void on_wire(M& m, P& p, F&& f) {
    f(m.n_operators, p.count);
    f(m.pi_thresholds_V, p.thresholds, p.count);
    f(m.pi_weights, p.weights, p.count);
  }
  static Params build(const Settings& s);  // throws ParameterError naming the field
  static Settings settings_of(const Params& p);
  static std::string summary_of(const Params& p);  // "15 plays up to 233.3 V"
};

struct LinearDescriptor : StoresParams<LinearDescriptor, LinearParams> {
  using Forward = LinearModel;
  using Inverse = LinearInverse;
  static constexpr std::string_view name = "linear";
  static constexpr std::string_view summary = "linear spring y = gain*u + offset (no hysteresis)";
  static constexpr ModelKind kind = ModelKind::linear;
  static constexpr auto in_set = &ModelParamSet::linear;
  static std::span<const ParamSpec<Settings>> table();
  template <class M, class P, class F>
  static void on_wire(M& m, P& p, F&& f) {
    f(m.linear_gain, p.gain);
    f(m.linear_offset_m, p.offset);
  }
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
  static constexpr ModelKind kind = ModelKind::katalenic;
  static constexpr auto in_set = &ModelParamSet::katalenic;
  static std::span<const ParamSpec<Settings>> table();
  template <class M, class P, class F>
  static void on_wire(M& m, P& p, F&& f) {
    f(m.kat_k1, p.k1);
    f(m.kat_k2, p.k2);
    f(m.kat_k2_slope, p.k2_slope);
    f(m.kat_k2_domain_min, p.k2_domain_min);
    f(m.kat_k2_domain_max, p.k2_domain_max);
    f(m.kat_initial_offset, p.initial_offset);
    shaping_on_wire(f, p.input_shaping, m.kat_in_shaping, m.kat_in_gain, m.kat_in_offset, m.kat_in_coefficients,
                    m.kat_in_domain_min, m.kat_in_domain_max, m.kat_in_amplitude, m.kat_in_scale);
    shaping_on_wire(f, p.output_shaping, m.kat_out_shaping, m.kat_out_gain, m.kat_out_offset, m.kat_out_coefficients,
                    m.kat_out_domain_min, m.kat_out_domain_max, m.kat_out_amplitude, m.kat_out_scale);
  }

 private:
  template <class F, class S, class K, class D, class C>
  static void shaping_on_wire(F& f, S& s, K& shaping_kind, D& gain, D& offset, C& coefficients, D& domain_min,
                              D& domain_max, D& amplitude, D& scale) {
    f(shaping_kind, s.kind);
    f(gain, s.gain);
    f(offset, s.offset);
    f(coefficients, s.coefficients);
    f(domain_min, s.domain_min);
    f(domain_max, s.domain_max);
    f(amplitude, s.amplitude);
    f(scale, s.scale);
  }
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

// The models a ModelParamSet holds, one for each ModelKind: what code over every such model
// iterates. F is a generic lambda []<class D>() {...} called with each model's descriptor.
template <class... D>
struct ModelList {
  static_assert(sizeof...(D) == kModelKindCount, "one descriptor per ModelKind");

  template <class F>
  static void for_each(F&& f) {
    (f.template operator()<D>(), ...);
  }
  // f for the model `kind` names; false when it names none.
  template <class F>
  static bool visit(ModelKind kind, F&& f) {
    return ((kind == D::kind && (f.template operator()<D>(), true)) || ...);
  }
};
using OnlineModels = ModelList<MemDescriptor, PiDescriptor, KatalenicDescriptor, LinearDescriptor>;

// "mem: c1 5.3e-09 m/V, c2 2.1e-12 m/V^(1+c3), c3 1.15": the set's model and its summary.
std::string describe_model(const ModelParamSet& set);

}  // namespace hystloop
