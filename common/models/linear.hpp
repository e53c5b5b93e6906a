#pragma once
// Static linear model y = gain u + offset: the "linear spring" feedforward the MEM paper compares
// against (its controller 1). No memory, so no hysteresis; only the swap needs state: set_params
// keeps the output continuous by shifting the offset it applies (params() still reports what was set).

namespace hystloop {

struct MemParams;

struct LinearParams {
  double gain = 6.34e-9;  // [m/V] the chord of MemParams::paper_like()'s +-250 V major loop
  double offset = 0.0;    // [m]

  void validate() const;  // gain finite and != 0 (the inverse divides by it), offset finite
};

// The linear spring through the ends of a MEM model's major loop for inputs within +-u_amplitude [V].
LinearParams linear_params_from_mem(const MemParams& mem, double u_amplitude);

// What the model and its inverse share: the parameters and, to keep the output continuous across
// set_params, the last input and the shift applied to the offset.
class LinearState {
 public:
  void reset(double x0 = 0.0) noexcept {  // x0: u0 [V] for the model, y0 [m] for the inverse
    x_ = x0;
    shift_ = 0.0;
  }
  const LinearParams& params() const noexcept { return params_; }

 protected:
  explicit LinearState(const LinearParams& params) : params_(params) { params_.validate(); }

  LinearParams params_;
  double x_ = 0.0;      // last u [V] (model) or y_ref [m] (inverse)
  double shift_ = 0.0;  // [m] added to the offset
};

// u [V] -> y [m].
class LinearModel : public LinearState {
 public:
  explicit LinearModel(const LinearParams& params = {}) : LinearState(params) {}
  double forward(double u) noexcept;
  void set_params(const LinearParams& params);  // validates; y does not jump
};

// y_ref [m] -> u [V].
class LinearInverse : public LinearState {
 public:
  explicit LinearInverse(const LinearParams& params = {}) : LinearState(params) {}
  double inverse(double y_ref) noexcept;
  void set_params(const LinearParams& params);  // validates; u does not jump
};

}  // namespace hystloop
