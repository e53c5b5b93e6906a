#pragma once
// Every online hysteresis model's inverse as the compensator drives it, behind one interface. The
// compensator keeps each model's parameters while another is in use (a model switch at run time
// takes the newest set of that model, and model_params() reports them all), so it holds one
// inverse for every model in OnlineModels. What differs between them (where an inverse starts,
// how it restarts at a reversal without a step, which slope it calls nominal) lives in the
// adapter each model's inverse selects below, and the compensator names a model, never switches
// on it. A value type: the compensator's dry runs copy it.

#include <cstddef>
#include <optional>
#include <tuple>

#include "models/model_descriptors.hpp"

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
  // Every model's inverse with its member of `params` (validated where they entered).
  explicit HysteresisInverses(const ModelParams& params);

  // y_ref [m] -> u [V] through `kind`'s inverse (one step of its state).
  double inverse(ModelKind kind, double y_ref_m) noexcept;
  // `kind`'s inverse starts a reference: at y0_m on a virgin stage, or, given where a moved stage
  // is, from there (MEM continues the stage's branch so the voltage does not jump; the others,
  // which keep no branch origin of their own, start at y0_m).
  void start(ModelKind kind, double y0_m, const std::optional<StagePoint>& at) noexcept;
  // Restarts `kind`'s inverse at a reversal at u_rev_V (model coordinates; the branch before it
  // began at u_prev_rev_V) without a step, where the hysteresis model's target is w_m; returns the
  // model's output there. MEM starts its branch at (w, u_rev); the line has no memory and restarts
  // on itself; every other model (PI, Katalenic) replays the branch through its forward model
  // (which sets every play / the operator the branch swept) and then through its inverse.
  double restart_at_reversal(ModelKind kind, double u_prev_rev_V, double u_rev_V, double w_m) noexcept;
  // The slope [m/V] the re-anchoring ramps with where no secant is known (MEM's c1, PI's first
  // weight; a model with no single one, as Katalenic's operator, uses the line's gain).
  double nominal_slope(ModelKind kind) const noexcept;

  // Takes the member of `set` that set.kind names (validated where it entered).
  void set_params(const ModelParamSet& set);
  // Every model's parameters (a ModelParamSet's kind is left as given).
  void get_params(ModelParams& params) const noexcept;
  // Every model's parameters from `other` (a restarted compensator keeps what it had).
  void take_params_from(const HysteresisInverses& other);

  const MemParams& mem_params() const noexcept {
    return std::get<Adapters::at<ModelKind::mem>>(adapters_).inv.params();
  }
  const LinearParams& linear_params() const noexcept {
    return std::get<Adapters::at<ModelKind::linear>>(adapters_).inv.params();
  }

 private:
  // Every model whose inverse is neither MEM's nor the line's (PI, Katalenic): an inverse and the
  // forward model that replays a branch into it.
  template <class D>
  struct Replayed {
    typename D::Inverse inv;
    typename D::Forward model;
    explicit Replayed(const ModelParams& p) : inv(p.*D::in_set), model(p.*D::in_set) {}
    void start(double y0_m, const std::optional<StagePoint>&) noexcept { inv.reset(y0_m); }
    double restart(double u_prev_rev_V, double u_rev_V, double w_m) noexcept;
    void set(const ModelParams& s) { inv.set_params(s.*D::in_set), model.set_params(s.*D::in_set); }
    void get(ModelParams& s) const noexcept { s.*D::in_set = inv.params(); }
  };
  // MEM's inverse remembers nothing but its branch's origin: it starts and restarts there.
  template <class D>
  struct Mem {
    typename D::Inverse inv;
    explicit Mem(const ModelParams& p) : inv(p.*D::in_set) {}
    void start(double y0_m, const std::optional<StagePoint>& at) noexcept;
    double restart(double u_prev_rev_V, double u_rev_V, double w_m) noexcept;
    void set(const ModelParams& s) { inv.set_params(s.*D::in_set); }
    void get(ModelParams& s) const noexcept { s.*D::in_set = inv.params(); }
  };
  // The line has no memory: it restarts on itself.
  template <class D>
  struct Linear {
    typename D::Inverse inv;
    explicit Linear(const ModelParams& p) : inv(p.*D::in_set) {}
    void start(double y0_m, const std::optional<StagePoint>&) noexcept { inv.reset(y0_m); }
    double restart(double u_prev_rev_V, double u_rev_V, double w_m) noexcept;
    void set(const ModelParams& s) { inv.set_params(s.*D::in_set); }
    void get(ModelParams& s) const noexcept { s.*D::in_set = inv.params(); }
  };

  // The adapter of model D, chosen by its inverse.
  template <class D, class Inverse = typename D::Inverse>
  struct AdapterFor {
    using type = Replayed<D>;
  };
  template <class D>
  struct AdapterFor<D, MemInverse> {
    using type = Mem<D>;
  };
  template <class D>
  struct AdapterFor<D, LinearInverse> {
    using type = Linear<D>;
  };
  template <class D>
  using Adapter = typename AdapterFor<D>::type;

  // One adapter per model of a model list, in its order; at<kind> is the place of kind's.
  template <class List>
  struct AdaptersOf;
  template <template <class...> class List, class... D>
  struct AdaptersOf<List<D...>> {
    using type = std::tuple<Adapter<D>...>;
    static type make(const ModelParams& p) { return type(Adapter<D>(p)...); }
    template <ModelKind Kind>
    static constexpr std::size_t at = [] {
      std::size_t i = 0;
      (void)((D::kind != Kind && (++i, true)) && ...);
      return i;
    }();
  };
  using Adapters = AdaptersOf<OnlineModels>;

  // f(the adapter of the model `kind` names); nothing for a kind that names none.
  template <class Self, class F>
  static void visit(Self& self, ModelKind kind, F&& f);

  Adapters::type adapters_;
};

}  // namespace hystloop
