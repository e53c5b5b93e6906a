#pragma once
// The online models' registry: every model the compensator can invert online and the
// re-identifier can fit, its descriptor, its number, its parameters' member and its feedforward
// mode, in one place. A parameter set of any of them (ModelParamSet) is what the re-identifier
// publishes (lcmtypes/model_params_t.lcm carries it on the wire) and what the compensator swaps in
// at a reversal. Code over every such model (the message and its checks, validation, plausibility,
// summaries, the compensator's config, modes and inverses) iterates OnlineModels and names none of
// them, so a model is added in its own files (its model; its table and gain band in
// <model>_descriptor.cpp) and here, and its fields on the wire in model_params_t.lcm. Banning's
// model needs its own experiments and is identified offline only, so it is not one of them.

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <span>
#include <vector>

#include "models/gain_plausibility.hpp"
#include "models/katalenic.hpp"
#include "models/linear.hpp"
#include "models/mem.hpp"
#include "models/param_text.hpp"
#include "models/prandtl_ishlinskii.hpp"
#include "models/stage_inverse.hpp"

namespace hystloop {

// A field of model_params_t as the exports name it: its name on the wire, its unit, a note.
struct WireName {
  const char* name;
  const char* unit;
  const char* note = "";
};

// Each model's descriptor, as types: the settings struct its parameter table writes into, how that
// becomes the model's parameter struct and back, a one-line summary of a set, the forward and
// inverse classes. on_wire(msg, params, f) calls f(its WireName, wire field, parameter field) for every field the
// model has on the wire (model_params_t, whose fields carry the model's prefix): one list for
// writing, reading, clearing and checking a message; check_wire the wire's sanity bounds for a
// message of its kind (a sender's units or corruption; the model's domain is validate()'s);
// gain_range and refuse_gain its small-signal gain band (gain_plausibility.hpp). M is the message
// type, so this layer needs no LCM. The tables, gains and summaries are in <model>_descriptor.cpp.

struct MemDescriptor : StoresParams<MemDescriptor, MemParams> {
  using Forward = MemModel;
  using Inverse = MemInverse;
  static constexpr std::string_view name = "mem";
  static constexpr std::string_view summary =
      "memory-element (Ramberg-Osgood) hysteresis, Strijbosch-Tiels-Oomen; exact inverse (Theorem 10)";
  static std::span<const ParamSpec<Settings>> table();
  template <class M, class P, class F>
  static void on_wire(M& m, P& p, F&& f) {
    f(WireName{"mem_c1", "m/V"}, m.mem_c1, p.c1);
    f(WireName{"mem_c2", "m/V^(1+c3)"}, m.mem_c2, p.c2);
    f(WireName{"mem_c3", "1"}, m.mem_c3, p.c3);
  }
  template <class M, class R>
  static void check_wire(const M& m, R&& require) {
    require(m.mem_c1 > 0.0 && m.mem_c1 <= 1.0);  // [m/V]
    require(m.mem_c2 >= 0.0);
    require(m.mem_c3 > 0.0 && m.mem_c3 <= 50.0);  // beyond ~50, p^c3 overflows for p of 100s of volts
  }
  static GainRange gain_range(const Params& p, const GainPlausibility& rig) noexcept;
  [[noreturn]] static void refuse_gain(const Params& p, const GainRange& g, const GainPlausibility& rig);
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
  // The arrays' first `count` entries are the wire's; reading, count shrinks to the shortest.
  template <class M, class P, class F>
  static void on_wire(M& m, P& p, F&& f) {
    f(WireName{"n_operators", "1"}, m.n_operators, p.count);
    f(WireName{"pi_thresholds_V", "V"}, m.pi_thresholds_V, p.thresholds, p.count);
    f(WireName{"pi_weights", "m/V"}, m.pi_weights, p.weights, p.count);
  }
  static Params build(const Settings& s);  // throws ParameterError naming the field
  static Settings settings_of(const Params& p);
  static std::string summary_of(const Params& p);  // "15 plays up to 233.3 V"
  // lcm/message_checks has checked that the arrays hold n_operators entries.
  template <class M, class R>
  static void check_wire(const M& m, R&& require) {
    require(m.n_operators >= 1);
    if (m.n_operators < 1) return;
    require(m.pi_thresholds_V[0] == 0.0 && m.pi_weights[0] > 0.0);
    for (std::size_t i = 1; i < m.pi_thresholds_V.size(); ++i) {
      require(m.pi_thresholds_V[i] > m.pi_thresholds_V[i - 1] && m.pi_thresholds_V[i] <= 1.0e4);  // [V]
    }
  }
  static GainRange gain_range(const Params& p, const GainPlausibility& rig) noexcept;
  [[noreturn]] static void refuse_gain(const Params& p, const GainRange& g, const GainPlausibility& rig);
};

struct LinearDescriptor : StoresParams<LinearDescriptor, LinearParams> {
  using Forward = LinearModel;
  using Inverse = LinearInverse;
  static constexpr std::string_view name = "linear";
  static constexpr std::string_view summary = "linear spring y = gain*u + offset (no hysteresis)";
  static std::span<const ParamSpec<Settings>> table();
  template <class M, class P, class F>
  static void on_wire(M& m, P& p, F&& f) {
    f(WireName{"linear_gain", "m/V"}, m.linear_gain, p.gain);
    f(WireName{"linear_offset_m", "m"}, m.linear_offset_m, p.offset);
  }
  template <class M, class R>
  static void check_wire(const M& m, R&& require) {
    require(m.linear_gain != 0.0 && std::fabs(m.linear_gain) <= 1.0);  // [m/V]
  }
  static GainRange gain_range(const Params& p, const GainPlausibility& rig) noexcept;
  [[noreturn]] static void refuse_gain(const Params& p, const GainRange& g, const GainPlausibility& rig);
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
  template <class M, class P, class F>
  static void on_wire(M& m, P& p, F&& f) {
    f(WireName{"kat_k1", "1", "operator units"}, m.kat_k1, p.k1);
    f(WireName{"kat_k2", "1"}, m.kat_k2, p.k2);
    f(WireName{"kat_k2_slope", "1"}, m.kat_k2_slope, p.k2_slope);
    f(WireName{"kat_k2_domain_min", "1"}, m.kat_k2_domain_min, p.k2_domain_min);
    f(WireName{"kat_k2_domain_max", "1"}, m.kat_k2_domain_max, p.k2_domain_max);
    f(WireName{"kat_initial_offset", "1"}, m.kat_initial_offset, p.initial_offset);
    static constexpr WireName in[] = {{"kat_in_shaping", "1"},    {"kat_in_gain", "1", "V -> operator units"},
                                      {"kat_in_offset", "1"},     {"kat_in_coefficients", "1"},
                                      {"kat_in_domain_min", "1"}, {"kat_in_domain_max", "1"},
                                      {"kat_in_amplitude", "1"},  {"kat_in_scale", "1"}};
    static constexpr WireName out[] = {{"kat_out_shaping", "1"},    {"kat_out_gain", "1", "operator units -> m"},
                                       {"kat_out_offset", "1"},     {"kat_out_coefficients", "1"},
                                       {"kat_out_domain_min", "1"}, {"kat_out_domain_max", "1"},
                                       {"kat_out_amplitude", "1"},  {"kat_out_scale", "1"}};
    shaping_on_wire(f, in, p.input_shaping, m.kat_in_shaping, m.kat_in_gain, m.kat_in_offset, m.kat_in_coefficients,
                    m.kat_in_domain_min, m.kat_in_domain_max, m.kat_in_amplitude, m.kat_in_scale);
    shaping_on_wire(f, out, p.output_shaping, m.kat_out_shaping, m.kat_out_gain, m.kat_out_offset,
                    m.kat_out_coefficients, m.kat_out_domain_min, m.kat_out_domain_max, m.kat_out_amplitude,
                    m.kat_out_scale);
  }
  template <class M, class R>
  static void check_wire(const M& m, R&& require) {
    require(m.kat_k1 > 0.0 && m.kat_k2 > 0.0 && m.kat_k2_domain_min < m.kat_k2_domain_max);
    require(m.kat_in_shaping >= M::SHAPING_LINEAR && m.kat_in_shaping <= M::SHAPING_TANH);
    require(m.kat_out_shaping >= M::SHAPING_LINEAR && m.kat_out_shaping <= M::SHAPING_TANH);
  }
  static GainRange gain_range(const Params& p, const GainPlausibility& rig) noexcept;
  [[noreturn]] static void refuse_gain(const Params& p, const GainRange& g, const GainPlausibility& rig);

 private:
  template <class F, class S, class K, class D, class C>
  static void shaping_on_wire(F& f, const WireName (&n)[8], S& s, K& kind, D& gain, D& offset, C& coefficients,
                              D& domain_min, D& domain_max, D& amplitude, D& scale) {
    f(n[0], kind, s.kind);
    f(n[1], gain, s.gain);
    f(n[2], offset, s.offset);
    f(n[3], coefficients, s.coefficients);
    f(n[4], domain_min, s.domain_min);
    f(n[5], domain_max, s.domain_max);
    f(n[6], amplitude, s.amplitude);
    f(n[7], scale, s.scale);
  }
};

// Numbering shared with model_params_t.kind on the wire; never renumber.
enum class ModelKind : std::int8_t { mem = 0, pi = 1, katalenic = 2, linear = 3 };
inline constexpr int kModelKindCount = 4;

// One parameter struct of every online model.
struct ModelParams {
  MemParams mem{};
  PiParams pi{};
  KatalenicParams katalenic{};
  LinearParams linear{};
};

struct ModelParamSet : ModelParams {
  ModelKind kind = ModelKind::mem;
  // Only the member that `kind` names is meaningful; the others keep their defaults.
  // The stage in series with the hysteresis, when the set says (nullopt: the receiver keeps the
  // stage it has; a hysteresis refit says nothing of the stage).
  std::optional<StageModel> stage;

  // Validates the member `kind` names (and the stage, at tick dt_s); throws ParameterError naming
  // the field ("pi.weights[3]", "stage.c").
  void validate(double dt_s = 1e-4) const;
};

// A model's descriptor as the registry places it: its kind, its member of ModelParams and the
// number of its feedforward mode (command_block_t.MODE_*, FeedforwardMode).
template <class Descriptor, ModelKind Kind, auto Member, std::int8_t Mode>
struct OnlineModel : Descriptor {
  static constexpr ModelKind kind = Kind;
  static constexpr auto in_set = Member;
  static constexpr std::int8_t mode = Mode;
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
using OnlineModels = ModelList<OnlineModel<MemDescriptor, ModelKind::mem, &ModelParams::mem, 2>,
                               OnlineModel<PiDescriptor, ModelKind::pi, &ModelParams::pi, 3>,
                               OnlineModel<KatalenicDescriptor, ModelKind::katalenic, &ModelParams::katalenic, 4>,
                               OnlineModel<LinearDescriptor, ModelKind::linear, &ModelParams::linear, 1>>;

std::string_view to_string(ModelKind kind) noexcept;
// Every ModelKind's name, in ModelKind order ("mem", "pi", "katalenic", "linear"): what help texts
// and refusals list as the models to choose from, so a model added to OnlineModels is listed
// without editing them.
std::vector<std::string_view> model_kind_names();
// One of model_kind_names(); nullopt for anything else.
std::optional<ModelKind> parse_model_kind(std::string_view name) noexcept;
// The wire's number; nullopt when it names no model.
std::optional<ModelKind> model_kind_from_int(std::int64_t value) noexcept;

// "mem: c1 5.3e-09 m/V, c2 2.1e-12 m/V^(1+c3), c3 1.15": the set's model and its summary.
std::string describe_model(const ModelParamSet& set);

}  // namespace hystloop
