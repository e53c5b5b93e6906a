#pragma once
// The Prandtl-Ishlinskii model's description: its parameter table (in pi_descriptor.cpp), its
// fields on the wire and their sanity bounds, its small-signal gain band. The online models'
// registry (model_set.hpp) gives it its kind, its member of ModelParams and its feedforward mode.

#include <cstddef>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "models/gain_band.hpp"
#include "models/mem.hpp"
#include "models/param_text.hpp"
#include "models/prandtl_ishlinskii.hpp"

namespace hystloop {

// on_wire(msg, params, f): f(wire field, parameter field) for every field the model has on the
// wire (model_params_t, whose fields carry the model's prefix), one list for writing, reading and
// clearing a message; M is the message type, so this layer needs no LCM.

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
    f(m.n_operators, p.count);
    f(m.pi_thresholds_V, p.thresholds, p.count);
    f(m.pi_weights, p.weights, p.count);
  }
  static Params build(const Settings& s);  // throws ParameterError naming the field
  static Settings settings_of(const Params& p);
  static std::string summary_of(const Params& p);  // "15 plays up to 233.3 V"
  // The wire's sanity bounds on a message of this kind (lcm/message_checks, which has checked the
  // arrays hold n_operators entries): require(bool) for each.
  template <class M, class R>
  static void check_wire(const M& m, R&& require) {
    require(m.n_operators >= 1);
    if (m.n_operators < 1) return;
    require(m.pi_thresholds_V[0] == 0.0 && m.pi_weights[0] > 0.0);
    for (std::size_t i = 1; i < m.pi_thresholds_V.size(); ++i) {
      require(m.pi_thresholds_V[i] > m.pi_thresholds_V[i - 1] && m.pi_thresholds_V[i] <= 1.0e4);  // [V]
    }
  }
  // The smallest and largest small-signal gain dy/du [m/V] anywhere on a branch the actuator can
  // run (gain_plausibility.hpp), and the refusal naming the parameter that leaves the band.
  static GainRange gain_range(const Params& p, const GainPlausibility& rig) noexcept;
  [[noreturn]] static void refuse_gain(const Params& p, const GainRange& g, const GainPlausibility& rig);
};

}  // namespace hystloop
