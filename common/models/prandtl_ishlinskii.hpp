#pragma once
// Classical Prandtl–Ishlinskii (PI) hysteresis, the baseline the MEM paper compares against
// (15 play operators, after Kuhnen 2003, its ref. [15]), u [V] -> y [m]:
//
//   y = sum_i w_i play_{r_i}[u],   play_r[u](k) = max(u(k) - r, min(u(k) + r, z(k-1))),
//
// with r_0 = 0 (play_0 is the identity, w_0 the slope right after a reversal). The operator count is
// fixed at compile time (at most kPiMaxOperators) so the state is a std::array: no allocation.
//
// The inverse is again a PI operator (Kuhnen 2003, eqs. (15)-(17); Krejčí's group property):
//
//   r'_i = sum_{j<=i} w_j (r_i - r_j),   w'_0 = 1 / w_0,
//   w'_i = -w_i / ((w_0 + ... + w_i)(w_0 + ... + w_{i-1})),   i >= 1,
//
// i.e. the inverse's loading curve (slopes 1/W_i between the r'_i, W_i = w_0 + ... + w_i) is the
// inverse function of the forward one. It is exact when both start from matching states, which
// reset(u0) / reset(y0 = forward output at u0) provide (both start demagnetised at 0, then move
// monotonically to their starting value).

#include <array>
#include <cstddef>

namespace hystloop {

struct MemParams;

inline constexpr std::size_t kPiMaxOperators = 32;

struct PiParams {
  std::size_t count = 0;                             // N, 1..kPiMaxOperators (the paper: 15)
  std::array<double, kPiMaxOperators> thresholds{};  // r_i [V]: r_0 = 0 < r_1 < ... < r_{N-1}
  std::array<double, kPiMaxOperators> weights{};     // w_i [m/V]

  // Throws ParameterError naming the field ("count", "thresholds[3]", "weights[0]"): w_0 > 0 and
  // every cumulative weight W_i = w_0 + ... + w_i > 0 (the loading curve strictly increasing, so
  // the operator is invertible; single w_i may be negative, as the inverse's are), thresholds
  // strictly increasing from r_0 = 0, everything finite.
  void validate() const;

  // count operators with r_i = i * max_threshold / count (i = 0..count-1), all weights 0 (to fill).
  static PiParams with_even_thresholds(std::size_t count, double max_threshold);
};

// The inverse PI operator's parameters (formula above). Validates `forward` first.
PiParams inverse_pi_params(const PiParams& forward);

// A PI approximation of a MEM model for inputs within +-u_amplitude [V]: both obey Masing's rule
// (branch = twice the skeleton at half scale), so matching the loading curve phi(r) to the MEM
// skeleton phi(r) = F(2r)/2 at evenly spaced thresholds makes the PI operator reproduce the MEM
// model exactly at every breakpoint, linear in between. The project's PI baseline.
PiParams pi_params_from_mem(const MemParams& mem, std::size_t count, double u_amplitude);

// u [V] -> y [m].
class PiModel {
 public:
  explicit PiModel(const PiParams& params);

  // Demagnetised at 0, then moved monotonically to u0.
  void reset(double u0 = 0.0) noexcept;
  double forward(double u) noexcept;

  // Validates; keeps each play state (clamped into its new band) and shifts the output so it does
  // not jump.
  void set_params(const PiParams& params);
  const PiParams& params() const noexcept { return params_; }

  double input() const noexcept { return u_; }
  double output() const noexcept { return y_; }

 private:
  double sum() const noexcept;

  PiParams params_;
  std::array<double, kPiMaxOperators> z_{};
  double u_ = 0.0;
  double y_ = 0.0;
  double y_shift_ = 0.0;  // [m] from set_params, so the output stays continuous
};

// y_ref [m] -> u [V]: the inverse PI operator, itself a PiModel on y.
class PiInverse {
 public:
  explicit PiInverse(const PiParams& params);

  // Demagnetised at 0, then moved monotonically to y0: matches PiModel::reset(u0) for y0 = its output.
  void reset(double y0 = 0.0) noexcept { inverse_.reset(y0); }
  double inverse(double y_ref) noexcept { return inverse_.forward(y_ref); }

  void set_params(const PiParams& params);  // validates; u does not jump
  const PiParams& params() const noexcept { return params_; }

  double output() const noexcept { return inverse_.output(); }

 private:
  PiParams params_;
  PiModel inverse_;
};

}  // namespace hystloop
