#pragma once
// The interface every hysteresis model in hystloop follows, checked at compile time instead of
// through a virtual base: the compensator and the simulator are templates over the model, so the
// per-sample call is a direct (inlinable) call.
//
//   struct XParams { ...fields with units...; void validate() const; };  // throws ParameterError
//   class XModel   { explicit XModel(const XParams&); void reset(double u0); double forward(double u);
//                    const XParams& params() const; void set_params(const XParams&); };  // u [V] -> y [m]
//   class XInverse { explicit XInverse(const XParams&); void reset(double y0); double inverse(double y_ref);
//                    const XParams& params() const; void set_params(const XParams&); };  // y [m] -> u [V]
//
// forward()/inverse() are noexcept, allocate nothing and keep fixed-size state. set_params()
// validates (it may throw) and keeps the current branch state: the output does not jump, the
// branch origin is re-anchored instead (the "bumpless swap" the compensator does at a reversal).

#include <concepts>
#include <type_traits>

namespace hystloop {

// A parameter set: a value type that can check itself (throws ParameterError naming the field).
template <class P>
concept ModelParameters = std::copyable<P> && requires(const P& p) {
  p.validate();
};

// The parameter type a model is built from, deduced from its params() accessor.
template <class M>
using model_params_t = std::remove_cvref_t<decltype(std::declval<const M&>().params())>;

// What a model and an inverse share: built from its parameters, reset to a point, its parameters
// read back and swapped.
template <class M>
concept SampleModel = ModelParameters<model_params_t<M>> && std::constructible_from < M,
        const model_params_t<M>
& > &&requires(M& m, const M& cm, double x) {
  m.reset(x);
  { cm.params() }
  noexcept->std::same_as<const model_params_t<M>&>;
  m.set_params(cm.params());
};

// u [V] -> y [m], sample by sample.
template <class M>
concept HysteresisForward = SampleModel<M> && requires(M& m, double u) {
  { m.forward(u) }
  noexcept->std::same_as<double>;
};

// y_ref [m] -> u [V], sample by sample (a feedforward compensator).
template <class M>
concept HysteresisInverse = SampleModel<M> && requires(M& m, double y) {
  { m.inverse(y) }
  noexcept->std::same_as<double>;
};

}  // namespace hystloop
