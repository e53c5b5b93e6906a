#pragma once
// Any linear stage in series with the hysteresis, as a lab's identification software prints it, and
// its exact sampled model at the bridge's tick.
//
// Banning's second order (models/second_order_stage.hpp) is one stage among many: a real piezo
// stage has several lightly damped modes, sometimes a non-minimum-phase zero (a mode that moves the
// other way first) and an input delay (amplifier, DAC, filters) that is rarely a whole number of
// ticks. LinearStageSpec takes the model in the forms such software prints:
//   (a) zeros / poles in Hz, s = 2 pi (real_hz + i imag_hz); an entry with imag_hz != 0 stands for
//       its conjugate pair, listed once;
//   (b) numerator / denominator polynomials in s, highest power first (as MATLAB prints them);
//   (c) a sum of modes: weight * wn^2 / (s^2 + 2 zeta wn s + wn^2) with wn = 2 pi frequency_hz,
//       the weights being each mode's share of the DC gain;
//   (d) a model already sampled at the tick: numerator / denominator in z^-1 (lowest power first)
//       in the convention below, with the dt it was sampled at;
// plus delay_s, an input delay in seconds (fractional ticks allowed, except for (d)).
//
// THE MODEL IS NORMALISED TO UNIT DC GAIN (the gain of the hysteresis model carries the scale, as
// for Banning's stage); a zero or non-finite DC gain is refused. A gain printed with the model is
// therefore ignored, its sign included.
//
// Sampling: EXACT ZERO-ORDER HOLD with a fractional input delay. The command w_k of tick k is held
// over tick k (the DAC) and y_k is the position at the END of tick k, the convention of
// models/stage_inverse.hpp: without delay y_k depends on w_k. A delay (d + f) dt, d whole, 0 <= f < 1,
// splits each held value across two sub-intervals of the tick: over tick k the stage sees w_{k-d-1}
// for f dt, then w_{k-d} for (1 - f) dt, so
//   x_{k+1} = Phi x_k + Gamma1 w_{k-d-1} + Gamma0 w_{k-d},
//   Gamma0 = int_0^{(1-f)dt} e^{As} ds B,  Gamma1 = e^{A(1-f)dt} int_0^{f dt} e^{As} ds B,
// all read off exponentials of the augmented matrix [A B; 0 0] (Eigen's Pade exponential, as in
// second_order_stage.cpp). The fraction adds one state (the previous held value) and a pole at 0;
// the whole ticks stay a pure delay z^-d in series (a ring buffer, not d states). The only error
// is rounding: tests/models/linear_stage_test.cpp checks a delayed first-order stage against its
// closed form and Banning's stage against discretise_zoh.
//
// The continuous model is realised as a cascade of first- and second-order sections (for (a), (b))
// or in parallel (for (c)), each section with unit DC gain and its state scaled by its natural
// frequency, so that every entry of the matrix exponential is O(omega dt).

#include <Eigen/Core>
#include <array>
#include <complex>
#include <cstdint>
#include <vector>

namespace hystloop {

struct LinearStageSpec {
  static constexpr int kMaxStates = 16;           // continuous order (the fractional delay adds one)
  static constexpr double kMaxDelayTicks = 50.0;  // 5 ms at 10 kHz: the preview must cover it

  enum class Form : std::int8_t { kZeroPoleGain = 0, kTransferFunction = 1, kModes = 2, kDiscrete = 3 };

  struct Root {  // s = 2 pi (real_hz + i imag_hz) [rad/s]; imag_hz != 0 stands for the conjugate pair
    double real_hz = 0.0;
    double imag_hz = 0.0;
  };
  struct Mode {
    double frequency_hz = 0.0;   // undamped natural frequency, > 0
    double damping_ratio = 0.0;  // > 0 (0 is marginal); >= 1 gives two real poles
    double weight = 1.0;         // share of the DC gain (the weights are normalised to sum to 1)
  };

  Form form = Form::kZeroPoleGain;
  std::vector<Root> zeros;               // (a)
  std::vector<Root> poles;               // (a)
  std::vector<double> numerator_s;       // (b) highest power of s first
  std::vector<double> denominator_s;     // (b)
  std::vector<Mode> modes;               // (c)
  std::vector<double> numerator_zinv;    // (d) lowest power of z^-1 first (leading zeros: whole ticks of delay)
  std::vector<double> denominator_zinv;  // (d)
  double discrete_dt_s = 0.0;            // (d) must equal the tick
  double delay_s = 0.0;                  // input delay [s], 0 .. kMaxDelayTicks ticks

  // Banning's y'' + c y' + k y = k w (SecondOrderStageParams' k [1/s^2], c [1/s]).
  static LinearStageSpec second_order(double k, double c);
  static LinearStageSpec zero_pole(std::vector<Root> zeros, std::vector<Root> poles, double delay_s = 0.0);
  static LinearStageSpec transfer_function(std::vector<double> numerator_s, std::vector<double> denominator_s,
                                           double delay_s = 0.0);
  static LinearStageSpec sum_of_modes(std::vector<Mode> modes, double delay_s = 0.0);
  static LinearStageSpec discrete(std::vector<double> numerator_zinv, std::vector<double> denominator_zinv, double dt_s,
                                  double delay_s = 0.0);

  // Throws ParameterError naming the field with the "stage." prefix ("stage.poles[2]: unstable
  // pole ...", "stage.delay_s: ..."): unstable or marginal poles, an improper model, more than
  // kMaxStates states, a zero or non-finite DC gain, a delay outside [0, kMaxDelayTicks] ticks, a
  // tick that is not finite and in [1e-7, 1] s. Non-minimum-phase zeros are accepted.
  void validate(double dt_s) const;

  int order() const;  // continuous states (validates the form, not the tick)
  // The continuous response at f [Hz], e^{-i 2 pi f delay_s} included, unit DC gain. Validates the
  // form (ParameterError). A form (d) model has no continuous response: its discrete one is given.
  std::complex<double> frequency_response(double f_hz) const;
};

// The sampled stage: G(z) = z^-delay_ticks (C (zI - A)^-1 B + D), i.e. with the state x_k at the
// start of tick k and v_k = w_{k - delay_ticks},
//   y_k = C x_k + D v_k,   x_{k+1} = A x_k + B v_k,
// where y_k is the position at the end of tick k. Fixed maximum size: copying or stepping it never
// allocates.
struct DiscreteLinearStage {
  static constexpr int kMaxStates = LinearStageSpec::kMaxStates + 1;
  static constexpr int kMaxDelayTicks = static_cast<int>(LinearStageSpec::kMaxDelayTicks);
  static constexpr int kMaxCoefficients = kMaxStates + kMaxDelayTicks + 1;

  using Matrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxStates, kMaxStates>;
  using Column = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxStates, 1>;
  using Row = Eigen::Matrix<double, 1, Eigen::Dynamic, Eigen::RowMajor, 1, kMaxStates>;
  using Roots = Eigen::Matrix<std::complex<double>, Eigen::Dynamic, 1, 0, kMaxStates, 1>;
  using Coefficients = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxCoefficients, 1>;

  double dt_s = 0.0;
  int delay_ticks = 0;  // the whole ticks of the delay, in series
  Matrix a;
  Column b;
  Row c;
  double d = 0.0;
  Roots zeros;  // of the rational part C (zI - A)^-1 B + D (as many as poles: D != 0)
  Roots poles;  // e^{p dt} of the continuous poles, and 0 for a fractional delay
  // G(z) = numerator(z^-1) / denominator(z^-1), lowest power of z^-1 first, the whole-tick delay
  // included (delay_ticks leading zeros); denominator[0] = 1.
  Coefficients numerator;
  Coefficients denominator;

  int states() const noexcept { return static_cast<int>(a.rows()); }
  // G(e^{i 2 pi f dt}), the whole-tick delay included.
  std::complex<double> frequency_response(double f_hz) const noexcept;
  double dc_gain() const noexcept;  // 1 to rounding
};

// Validates (ParameterError, see LinearStageSpec::validate) and samples the stage at tick dt_s.
// Also refused: a model whose response to the first tick's command is exactly zero ("stage.delay_s":
// a delay that is a hair short of a whole tick; round it).
DiscreteLinearStage discretise(const LinearStageSpec& spec, double dt_s);

class LinearStageSimulator {
 public:
  explicit LinearStageSimulator(const DiscreteLinearStage& stage);

  // At rest at y0: the equilibrium for the input held at y0 for ever.
  void reset(double y0 = 0.0) noexcept;
  // Holds w over one tick and returns y at its end. A non-finite w returns NaN and leaves the state
  // untouched. Allocation free.
  double step(double w) noexcept;

  const DiscreteLinearStage& stage() const noexcept { return stage_; }

 private:
  DiscreteLinearStage stage_;
  DiscreteLinearStage::Column x_;                                          // state at the start of the tick
  DiscreteLinearStage::Column x_next_;                                     // scratch
  DiscreteLinearStage::Column x_rest_;                                     // equilibrium state per unit input
  std::array<double, DiscreteLinearStage::kMaxDelayTicks + 1> delayed_{};  // ring of past inputs
  int head_ = 0;
};

}  // namespace hystloop
