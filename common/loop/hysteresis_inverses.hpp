#pragma once
// Every hysteresis model's inverse as the compensator drives it, behind one interface. The
// compensator keeps each model's parameters while another is in use (a model switch at run time
// takes the newest set of that model, and model_params() reports them all), so it holds all four;
// what differs between them (where an inverse starts, how it restarts at a reversal without a
// step, which slope it calls nominal) lives in one adapter per model below, and the compensator
// names a model, never switches on it. A value type: the compensator's dry runs copy it.

#include <optional>

#include "models/katalenic.hpp"
#include "models/linear.hpp"
#include "models/mem.hpp"
#include "models/model_set.hpp"
#include "models/prandtl_ishlinskii.hpp"

namespace hystloop {

// Where a stage that has moved was measured: on the branch that began at branch_u_V (NaN: not
// known) and passes through (u_V, y_m).
struct StagePoint {
  double u_V;
  double y_m;
  double branch_u_V;
};

class HysteresisInverses {
 public:
  HysteresisInverses(const MemParams& mem, const PiParams& pi, const KatalenicParams& katalenic,
                     const LinearParams& linear);

  // y_ref [m] -> u [V] through `kind`'s inverse (one step of its state).
  double inverse(ModelKind kind, double y_ref_m) noexcept;
  // `kind`'s inverse starts a reference: at y0_m on a virgin stage, or, given where a moved stage
  // is, from there (MEM continues the stage's branch so the voltage does not jump; the others,
  // which keep no branch origin of their own, start at y0_m).
  void start(ModelKind kind, double y0_m, const std::optional<StagePoint>& at) noexcept;
  // Restarts `kind`'s inverse at a reversal at u_rev_V (model coordinates; the branch before it
  // began at u_prev_rev_V) without a step, where the hysteresis model's target is w_m; returns the
  // model's output there. MEM starts its branch at (w, u_rev); PI and Katalenic replay the branch
  // through their forward model (which sets every play / the operator the branch swept) and then
  // through the inverse; the line has no memory and restarts on itself.
  double restart_at_reversal(ModelKind kind, double u_prev_rev_V, double u_rev_V, double w_m) noexcept;
  // The slope [m/V] the re-anchoring ramps with where no secant is known (MEM's c1, PI's first
  // weight; Katalenic's operator has no single one and uses the line's gain).
  double nominal_slope(ModelKind kind) const noexcept;

  // Takes the member of `set` that set.kind names (validated where it entered).
  void set_params(const ModelParamSet& set);
  // Every model's parameters; kind is left as given.
  void get_params(ModelParamSet& set) const noexcept;
  // All four models' parameters from `other` (a restarted compensator keeps what it had).
  void take_params_from(const HysteresisInverses& other);

  const MemParams& mem_params() const noexcept { return mem_.inv.params(); }
  const LinearParams& linear_params() const noexcept { return linear_.inv.params(); }

 private:
  struct Mem {
    MemInverse inv;
    void start(double y0_m, const std::optional<StagePoint>& at) noexcept;
    double restart(double u_prev_rev_V, double u_rev_V, double w_m) noexcept;
    void set(const ModelParamSet& s) { inv.set_params(s.mem); }
    void get(ModelParamSet& s) const noexcept { s.mem = inv.params(); }
  };
  // PI and Katalenic: an inverse and the forward model that replays a branch into it.
  template <class Model, class Inverse, auto Member>
  struct Replayed {
    Inverse inv;
    Model model;
    void start(double y0_m, const std::optional<StagePoint>&) noexcept { inv.reset(y0_m); }
    double restart(double u_prev_rev_V, double u_rev_V, double w_m) noexcept;
    void set(const ModelParamSet& s) { inv.set_params(s.*Member), model.set_params(s.*Member); }
    void get(ModelParamSet& s) const noexcept { s.*Member = inv.params(); }
  };
  struct Linear {
    LinearInverse inv;
    void start(double y0_m, const std::optional<StagePoint>&) noexcept { inv.reset(y0_m); }
    double restart(double u_prev_rev_V, double u_rev_V, double w_m) noexcept;
    void set(const ModelParamSet& s) { inv.set_params(s.linear); }
    void get(ModelParamSet& s) const noexcept { s.linear = inv.params(); }
  };
  using Pi = Replayed<PiModel, PiInverse, &ModelParamSet::pi>;
  using Katalenic = Replayed<KatalenicModel, KatalenicInverse, &ModelParamSet::katalenic>;

  // The one place a model kind picks its adapter.
  template <class Self, class F>
  static decltype(auto) visit(Self& self, ModelKind kind, F&& f);

  Mem mem_;
  Pi pi_;
  Katalenic katalenic_;
  Linear linear_;
};

}  // namespace hystloop
