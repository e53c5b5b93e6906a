#pragma once
// The Katalenic operator's description: its parameter table (in katalenic_descriptor.cpp), its
// fields on the wire and their sanity bounds, its small-signal gain band. The online models'
// registry (model_set.hpp) gives it its kind, its member of ModelParams and its feedforward mode.

#include <span>
#include <string_view>

#include "models/gain_band.hpp"
#include "models/katalenic.hpp"
#include "models/param_text.hpp"

namespace hystloop {

// on_wire(msg, params, f): f(wire field, parameter field) for every field the model has on the
// wire (model_params_t, whose fields carry the model's prefix), one list for writing, reading and
// clearing a message; M is the message type, so this layer needs no LCM.

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

  // The wire's sanity bounds on a message of this kind (lcm/message_checks): require(bool) for each.
  template <class M, class R>
  static void check_wire(const M& m, R&& require) {
    require(m.kat_k1 > 0.0 && m.kat_k2 > 0.0 && m.kat_k2_domain_min < m.kat_k2_domain_max);
    require(m.kat_in_shaping >= M::SHAPING_LINEAR && m.kat_in_shaping <= M::SHAPING_TANH);
    require(m.kat_out_shaping >= M::SHAPING_LINEAR && m.kat_out_shaping <= M::SHAPING_TANH);
  }
  // The smallest and largest small-signal gain dy/du [m/V] anywhere on a branch the actuator can
  // run (gain_plausibility.hpp), and the refusal naming the parameter that leaves the band.
  static GainRange gain_range(const Params& p, const GainPlausibility& rig) noexcept;
  [[noreturn]] static void refuse_gain(const Params& p, const GainRange& g, const GainPlausibility& rig);

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

}  // namespace hystloop
