#pragma once
// hystloop-model's loops over a model of the registry (a descriptor D of models/model_set.hpp):
// forward from reset(u[0]), and the inverse from reset(y_ref[0]). One definition for the tool and
// for the Python module, so that both compute the same numbers.

#include <concepts>
#include <cstddef>
#include <span>
#include <type_traits>

#include "models/model_concepts.hpp"

namespace hystloop::model_tool {

// A model with dynamics: the input is held for dt [s] (the Banning stage).
template <class M>
concept SteppedStage = requires(M& m, const M& cm, double u, double dt) {
  m.reset(u);
  { m.step(u, dt) }
  noexcept->std::same_as<double>;
  { cm.output() }
  noexcept->std::same_as<double>;
};

template <class D>
inline constexpr bool kHasInverse = !std::is_void_v<typename D::Inverse>;

// y[k] for u[k]; a stage's row k holds u[k] from t[k-1] to t[k] (t unused by a static map).
// u, y (and t for a stage) of one length.
template <class D>
void run_forward(const typename D::Params& params, std::span<const double> t, std::span<const double> u,
                 std::span<double> y) {
  using Forward = typename D::Forward;
  static_assert(HysteresisForward<Forward> || SteppedStage<Forward>);
  if (u.empty()) return;
  Forward model(params);
  model.reset(u.front());
  if constexpr (HysteresisForward<Forward>) {
    for (std::size_t k = 0; k < u.size(); ++k) y[k] = model.forward(u[k]);
  } else {
    // Row k: u[k] held from t[k-1] to t[k], y[k] at t[k]; the first row is the equilibrium at u[0].
    y[0] = model.output();
    for (std::size_t k = 1; k < u.size(); ++k) y[k] = model.step(u[k], t[k] - t[k - 1]);
  }
}

// u[k] for y_ref[k], of a model with an inverse (kHasInverse<D>).
template <class D>
requires kHasInverse<D>
void run_inverse(const typename D::Params& params, std::span<const double> y_ref, std::span<double> u) {
  using Inverse = typename D::Inverse;
  static_assert(HysteresisInverse<Inverse>);
  if (y_ref.empty()) return;
  Inverse inv(params);
  inv.reset(y_ref.front());
  for (std::size_t k = 0; k < y_ref.size(); ++k) u[k] = inv.inverse(y_ref[k]);
}

}  // namespace hystloop::model_tool
