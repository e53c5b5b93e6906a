#pragma once
// The memory-element model's description: its parameter table (in mem_descriptor.cpp), its fields
// on the wire and their sanity bounds, its small-signal gain band. The online models' registry
// (model_set.hpp) gives it its kind, its member of ModelParams and its feedforward mode.

#include <span>
#include <string_view>

#include "models/gain_band.hpp"
#include "models/mem.hpp"
#include "models/param_text.hpp"

namespace hystloop {

// on_wire(msg, params, f): f(wire field, parameter field) for every field the model has on the
// wire (model_params_t, whose fields carry the model's prefix), one list for writing, reading and
// clearing a message; M is the message type, so this layer needs no LCM.

struct MemDescriptor : StoresParams<MemDescriptor, MemParams> {
  using Forward = MemModel;
  using Inverse = MemInverse;
  static constexpr std::string_view name = "mem";
  static constexpr std::string_view summary =
      "memory-element (Ramberg-Osgood) hysteresis, Strijbosch-Tiels-Oomen; exact inverse (Theorem 10)";
  static std::span<const ParamSpec<Settings>> table();
  template <class M, class P, class F>
  static void on_wire(M& m, P& p, F&& f) {
    f(m.mem_c1, p.c1);
    f(m.mem_c2, p.c2);
    f(m.mem_c3, p.c3);
  }
  // The wire's sanity bounds on a message of this kind (lcm/message_checks: a sender's units or
  // corruption, not the model's domain, which validate() checks): require(bool) for each.
  template <class M, class R>
  static void check_wire(const M& m, R&& require) {
    require(m.mem_c1 > 0.0 && m.mem_c1 <= 1.0);  // [m/V]
    require(m.mem_c2 >= 0.0);
    require(m.mem_c3 > 0.0 && m.mem_c3 <= 50.0);  // beyond ~50, p^c3 overflows for p of 100s of volts
  }
  // The smallest and largest small-signal gain dy/du [m/V] anywhere on a branch the actuator can
  // run (gain_plausibility.hpp), and the refusal naming the parameter that leaves the band.
  static GainRange gain_range(const Params& p, const GainPlausibility& rig) noexcept;
  [[noreturn]] static void refuse_gain(const Params& p, const GainRange& g, const GainPlausibility& rig);
};

}  // namespace hystloop
