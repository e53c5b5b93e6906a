#include "loop/hysteresis_inverses.hpp"

#include <cmath>
#include <limits>

namespace hystloop {
namespace {

// The slope a model calls nominal, for the models that have a single one.
double nominal_slope_of(const MemParams& p) noexcept { return p.c1; }
double nominal_slope_of(const PiParams& p) noexcept { return p.weights[0]; }
double nominal_slope_of(const LinearParams& p) noexcept { return p.gain; }

}  // namespace

HysteresisInverses::HysteresisInverses(const ModelParams& params) : adapters_(Adapters::make(params)) {}

template <class Self, class F>
void HysteresisInverses::visit(Self& self, ModelKind kind, F&& f) {
  OnlineModels::visit(kind, [&]<class D>() { f(std::get<Adapter<D>>(self.adapters_)); });
}

template <class D>
void HysteresisInverses::Mem<D>::start(double y0_m, const std::optional<StagePoint>& at) noexcept {
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

template <class D>
double HysteresisInverses::Mem<D>::restart(double, double u_rev_V, double w_m) noexcept {
  inv.reset_to_branch(w_m, u_rev_V);  // MEM remembers nothing but the branch's origin
  return w_m;
}

template <class D>
double HysteresisInverses::Replayed<D>::restart(double u_prev_rev_V, double u_rev_V, double) noexcept {
  // The state a periodic input leaves at a reversal: the monotone branch from the previous
  // reversal to this one (from a virgin start there), through the model and then the inverse.
  model.reset(u_prev_rev_V);
  const double y_from = model.output();
  const double y_to = model.forward(u_rev_V);
  inv.reset(y_from);
  inv.inverse(y_to);
  return y_to;
}

template <class D>
double HysteresisInverses::Linear<D>::restart(double, double u_rev_V, double) noexcept {
  const double y0 = inv.params().gain * u_rev_V + inv.params().offset;
  inv.reset(y0);
  return y0;
}

// Kinds are checked where they enter; one that named no model would give NaN here.
double HysteresisInverses::inverse(ModelKind kind, double y_ref_m) noexcept {
  double u = std::numeric_limits<double>::quiet_NaN();
  visit(*this, kind, [&](auto& a) noexcept { u = a.inv.inverse(y_ref_m); });
  return u;
}

void HysteresisInverses::start(ModelKind kind, double y0_m, const std::optional<StagePoint>& at) noexcept {
  visit(*this, kind, [&](auto& a) noexcept { a.start(y0_m, at); });
}

double HysteresisInverses::restart_at_reversal(ModelKind kind, double u_prev_rev_V, double u_rev_V,
                                               double w_m) noexcept {
  double y = std::numeric_limits<double>::quiet_NaN();
  visit(*this, kind, [&](auto& a) noexcept { y = a.restart(u_prev_rev_V, u_rev_V, w_m); });
  return y;
}

double HysteresisInverses::nominal_slope(ModelKind kind) const noexcept {
  double slope = linear_params().gain;  // a model with no single slope ramps with the line's
  visit(*this, kind, [&](const auto& a) noexcept {
    if constexpr (requires { nominal_slope_of(a.inv.params()); }) slope = nominal_slope_of(a.inv.params());
  });
  return slope;
}

void HysteresisInverses::set_params(const ModelParamSet& set) {
  visit(*this, set.kind, [&](auto& a) { a.set(set); });
}

void HysteresisInverses::get_params(ModelParams& params) const noexcept {
  std::apply([&](const auto&... a) { (a.get(params), ...); }, adapters_);
}

void HysteresisInverses::take_params_from(const HysteresisInverses& other) {
  ModelParams all;
  other.get_params(all);
  std::apply([&](auto&... a) { (a.set(all), ...); }, adapters_);
}

}  // namespace hystloop
