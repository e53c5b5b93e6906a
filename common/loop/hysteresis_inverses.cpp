#include "loop/hysteresis_inverses.hpp"

#include <cmath>

namespace hystloop {

HysteresisInverses::HysteresisInverses(const MemParams& mem, const PiParams& pi, const KatalenicParams& katalenic,
                                       const LinearParams& linear)
    : mem_{MemInverse(mem)},
      pi_{PiInverse(pi), PiModel(pi)},
      katalenic_{KatalenicInverse(katalenic), KatalenicModel(katalenic)},
      linear_{LinearInverse(linear)} {}

template <class Self, class F>
decltype(auto) HysteresisInverses::visit(Self& self, ModelKind kind, F&& f) {
  switch (kind) {
    case ModelKind::mem: return f(self.mem_);
    case ModelKind::pi: return f(self.pi_);
    case ModelKind::katalenic: return f(self.katalenic_);
    case ModelKind::linear: break;
  }
  return f(self.linear_);
}

void HysteresisInverses::Mem::start(double y0_m, const std::optional<StagePoint>& at) noexcept {
  // A virgin stage starts on the skeleton; one that has moved (after an experiment or a mode
  // switch) is on a branch through where it is now, and the voltage must not jump.
  if (at && std::isfinite(at->branch_u_V)) {
    // The stage is on the branch that began at branch_u_V (the experiment's last reversal) and
    // passes through the measured (u, y): continue it there, direction and all.
    inv.continue_branch(at->branch_u_V, at->u_V, at->y_m);
  } else if (at) {
    inv.reset_to_branch(at->y_m, at->u_V);
  } else {
    inv.reset(y0_m);
  }
}

double HysteresisInverses::Mem::restart(double, double u_rev_V, double w_m) noexcept {
  inv.reset_to_branch(w_m, u_rev_V);  // MEM remembers nothing but the branch's origin
  return w_m;
}

template <class Model, class Inverse, auto Member>
double HysteresisInverses::Replayed<Model, Inverse, Member>::restart(double u_prev_rev_V, double u_rev_V,
                                                                     double) noexcept {
  // The state a periodic input leaves at a reversal: the monotone branch from the previous
  // reversal to this one (from a virgin start there), through the model and then the inverse.
  model.reset(u_prev_rev_V);
  const double y_from = model.output();
  const double y_to = model.forward(u_rev_V);
  inv.reset(y_from);
  inv.inverse(y_to);
  return y_to;
}

double HysteresisInverses::Linear::restart(double, double u_rev_V, double) noexcept {
  const double y0 = inv.params().gain * u_rev_V + inv.params().offset;
  inv.reset(y0);
  return y0;
}

double HysteresisInverses::inverse(ModelKind kind, double y_ref_m) noexcept {
  return visit(*this, kind, [&](auto& m) noexcept { return m.inv.inverse(y_ref_m); });
}

void HysteresisInverses::start(ModelKind kind, double y0_m, const std::optional<StagePoint>& at) noexcept {
  visit(*this, kind, [&](auto& m) noexcept { m.start(y0_m, at); });
}

double HysteresisInverses::restart_at_reversal(ModelKind kind, double u_prev_rev_V, double u_rev_V,
                                               double w_m) noexcept {
  return visit(*this, kind, [&](auto& m) noexcept { return m.restart(u_prev_rev_V, u_rev_V, w_m); });
}

double HysteresisInverses::nominal_slope(ModelKind kind) const noexcept {
  if (kind == ModelKind::mem) return mem_.inv.params().c1;
  if (kind == ModelKind::pi) return pi_.inv.params().weights[0];
  return linear_.inv.params().gain;
}

void HysteresisInverses::set_params(const ModelParamSet& set) {
  visit(*this, set.kind, [&](auto& m) { m.set(set); });
}

void HysteresisInverses::get_params(ModelParamSet& set) const noexcept {
  mem_.get(set);
  pi_.get(set);
  katalenic_.get(set);
  linear_.get(set);
}

void HysteresisInverses::take_params_from(const HysteresisInverses& other) {
  ModelParamSet all;
  other.get_params(all);
  for (const ModelKind kind : {ModelKind::mem, ModelKind::pi, ModelKind::katalenic, ModelKind::linear}) {
    all.kind = kind;
    set_params(all);
  }
}

}  // namespace hystloop
