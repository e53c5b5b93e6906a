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

// u [V] -> y [m].
class LinearModel {
 public:
  explicit LinearModel(const LinearParams& params = {});
  void reset(double u0 = 0.0) noexcept;
  double forward(double u) noexcept;
  void set_params(const LinearParams& params);  // validates; y does not jump
  const LinearParams& params() const noexcept { return params_; }

 private:
  LinearParams params_;
  double u_ = 0.0;
  double shift_ = 0.0;  // [m]
};

// y_ref [m] -> u [V].
class LinearInverse {
 public:
  explicit LinearInverse(const LinearParams& params = {});
  void reset(double y0 = 0.0) noexcept;
  double inverse(double y_ref) noexcept;
  void set_params(const LinearParams& params);  // validates; u does not jump
  const LinearParams& params() const noexcept { return params_; }

 private:
  LinearParams params_;
  double y_ = 0.0;
  double shift_ = 0.0;  // [m] subtracted from y_ref
};

}  // namespace hystloop
