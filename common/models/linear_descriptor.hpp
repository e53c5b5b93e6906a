#pragma once
// The linear model's description: its parameter table (in linear_descriptor.cpp), its fields on the
// wire and their sanity bounds, its small-signal gain band. The online models' registry
// (model_set.hpp) gives it its kind, its member of ModelParams and its feedforward mode.

#include <cmath>
#include <span>
#include <string_view>

#include "models/gain_band.hpp"
#include "models/linear.hpp"
#include "models/param_text.hpp"

namespace hystloop {

// on_wire(msg, params, f): f(wire field, parameter field) for every field the model has on the
// wire (model_params_t, whose fields carry the model's prefix), one list for writing, reading and
// clearing a message; M is the message type, so this layer needs no LCM.

struct LinearDescriptor : StoresParams<LinearDescriptor, LinearParams> {
  using Forward = LinearModel;
  using Inverse = LinearInverse;
  static constexpr std::string_view name = "linear";
  static constexpr std::string_view summary = "linear spring y = gain*u + offset (no hysteresis)";
  static std::span<const ParamSpec<Settings>> table();
  template <class M, class P, class F>
  static void on_wire(M& m, P& p, F&& f) {
    f(m.linear_gain, p.gain);
    f(m.linear_offset_m, p.offset);
  }
  // The wire's sanity bounds on a message of this kind (lcm/message_checks): require(bool).
  template <class M, class R>
  static void check_wire(const M& m, R&& require) {
    require(m.linear_gain != 0.0 && std::fabs(m.linear_gain) <= 1.0);  // [m/V]
  }
  // The smallest and largest small-signal gain dy/du [m/V] anywhere on a branch the actuator can
  // run (gain_plausibility.hpp), and the refusal naming the parameter that leaves the band.
  static GainRange gain_range(const Params& p, const GainPlausibility& rig) noexcept;
  [[noreturn]] static void refuse_gain(const Params& p, const GainRange& g, const GainPlausibility& rig);
};

}  // namespace hystloop
