#include "models/linear_stage.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>
#include <utility>

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <unsupported/Eigen/MatrixFunctions>

#include "core/errors.hpp"

namespace hystloop {
namespace {

using Complex = std::complex<double>;
constexpr double kTwoPi = 2.0 * std::numbers::pi;

// The continuous model, unit DC gain: x' = A x + B u, y = C x + D u. Poles in rad/s, every one listed.
struct Continuous {
  Eigen::MatrixXd a;
  Eigen::VectorXd b;
  Eigen::RowVectorXd c;
  double d = 1.0;
  std::vector<Complex> poles;
};

// A real root or a conjugate pair (imag > 0 stands for both) [rad/s].
struct Factor {
  Complex root;
  bool pair = false;
  int states() const { return pair ? 2 : 1; }
};

std::string hz_text(Complex s) {
  return number_text(s.real() / kTwoPi) + (s.imag() < 0 ? " - " : " + ") + number_text(std::abs(s.imag()) / kTwoPi) +
         "i Hz";
}

std::string index_field(const std::string& name, std::size_t i) { return name + "[" + std::to_string(i) + "]"; }

// Roots of a polynomial, highest power first (leading coefficient non-zero), through the
// eigenvalues of the companion matrix of the polynomial in s / scale, scale the geometric mean of
// the roots' magnitudes (so that kHz roots do not give coefficients of 1e70).
std::vector<Complex> polynomial_roots(const std::vector<double>& p) {
  const int n = static_cast<int>(p.size()) - 1;
  if (n <= 0) return {};
  const double scale = p[n] != 0.0 ? std::pow(std::abs(p[n] / p[0]), 1.0 / n) : 1.0;
  Eigen::MatrixXd companion = Eigen::MatrixXd::Zero(n, n);
  for (int j = 1; j <= n; ++j) companion(0, j - 1) = -p[j] / (p[0] * std::pow(scale, j));
  for (int i = 1; i < n; ++i) companion(i, i - 1) = 1.0;
  const Eigen::EigenSolver<Eigen::MatrixXd> eig(companion, false);
  std::vector<Complex> roots;
  roots.reserve(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) roots.push_back(eig.eigenvalues()(i) * scale);
  return roots;
}

// Real roots and one of each conjugate pair (the roots of a real polynomial).
std::vector<Factor> factors_of(const std::vector<Complex>& roots) {
  std::vector<Factor> out;
  for (const Complex r : roots) {
    if (std::abs(r.imag()) <= 1e-9 * std::abs(r)) {
      out.push_back({{r.real(), 0.0}, false});
    } else if (r.imag() > 0.0) {
      out.push_back({r, true});
    }
  }
  return out;
}

std::vector<Complex> all_roots(const std::vector<Factor>& factors) {
  std::vector<Complex> roots;
  for (const Factor& f : factors) {
    roots.push_back(f.root);
    if (f.pair) roots.push_back(std::conj(f.root));
  }
  return roots;
}

struct Section {  // x' = A x + B u, y = C x + D u
  Eigen::MatrixXd a;
  Eigen::VectorXd b;
  Eigen::RowVectorXd c;
  double d = 0.0;
};

// (n2 s^2 + n1 s + n0) / (s^2 + a1 s + a0) or (n1 s + n0) / (s + a0), scaled to unit DC gain
// (n0 = a0), the state scaled by the section's natural frequency.
Section make_section(const std::vector<Factor>& poles, const std::vector<Factor>& zeros) {
  // Monic polynomials, lowest power first.
  auto monic = [](const std::vector<Factor>& fs) {
    std::vector<double> p{1.0};
    for (const Factor& f : fs) {
      std::vector<double> q;
      if (f.pair) {
        q = {std::norm(f.root), -2.0 * f.root.real(), 1.0};
      } else {
        q = {-f.root.real(), 1.0};
      }
      std::vector<double> r(p.size() + q.size() - 1, 0.0);
      for (std::size_t i = 0; i < p.size(); ++i)
        for (std::size_t j = 0; j < q.size(); ++j) r[i + j] += p[i] * q[j];
      p = r;
    }
    return p;
  };
  const std::vector<double> den = monic(poles);
  std::vector<double> num = monic(zeros);
  const int order = static_cast<int>(den.size()) - 1;
  num.resize(den.size(), 0.0);
  const double g = den[0] / num[0];  // num[0] != 0: a zero at s = 0 is refused before
  for (double& v : num) v *= g;
  Section s;
  if (order == 1) {
    const double a0 = den[0];
    s.a = Eigen::MatrixXd::Constant(1, 1, -a0);
    s.b = Eigen::VectorXd::Constant(1, a0);
    s.d = num[1];
    s.c = Eigen::RowVectorXd::Constant(1, (num[0] - num[1] * a0) / a0);
  } else {
    const double a0 = den[0], a1 = den[1];
    const double w = std::sqrt(a0);
    s.a.resize(2, 2);
    s.a << 0.0, w, -w, -a1;
    s.b.resize(2);
    s.b << 0.0, w;
    s.d = num[2];
    const double c1 = num[1] - num[2] * a1, c0 = num[0] - num[2] * a0;
    s.c.resize(2);
    s.c << c0 / (w * w), c1 / w;
  }
  return s;
}

// Sections in series: first s1, then s2.
Continuous series(const Continuous& s1, const Section& s2) {
  const Eigen::Index n1 = s1.a.rows(), n2 = s2.a.rows();
  Continuous out;
  out.a = Eigen::MatrixXd::Zero(n1 + n2, n1 + n2);
  out.a.topLeftCorner(n1, n1) = s1.a;
  out.a.bottomLeftCorner(n2, n1) = s2.b * s1.c;
  out.a.bottomRightCorner(n2, n2) = s2.a;
  out.b.resize(n1 + n2);
  out.b << s1.b, s2.b * s1.d;
  out.c.resize(n1 + n2);
  out.c << s2.d * s1.c, s2.c;
  out.d = s2.d * s1.d;
  out.poles = s1.poles;
  return out;
}

// A cascade of first- and second-order sections with unit DC gain each. The caller checked that
// there are no more zeros than poles and no zero at s = 0.
Continuous cascade(const std::vector<Factor>& poles, std::vector<Factor> zeros) {
  // Sections of poles: each pair alone, the real poles two by two.
  std::vector<std::vector<Factor>> section_poles, section_zeros;
  std::vector<Factor> reals;
  for (const Factor& p : poles) {
    if (p.pair) {
      section_poles.push_back({p});
    } else {
      reals.push_back(p);
    }
  }
  for (std::size_t i = 0; i < reals.size(); i += 2) {
    section_poles.push_back({reals[i]});
    if (i + 1 < reals.size()) section_poles.back().push_back(reals[i + 1]);
  }
  section_zeros.resize(section_poles.size());
  auto room = [&](std::size_t i) {
    int n = 0, z = 0;
    for (const Factor& f : section_poles[i]) n += f.states();
    for (const Factor& f : section_zeros[i]) z += f.states();
    return n - z;
  };
  // Pairs of zeros first (they need a section of two poles with room for both), then the reals.
  std::stable_partition(zeros.begin(), zeros.end(), [](const Factor& f) { return f.pair; });
  for (const Factor& z : zeros) {
    for (std::size_t i = 0; i < section_poles.size(); ++i) {
      if (room(i) >= z.states()) {
        section_zeros[i].push_back(z);
        break;
      }
    }
  }
  Continuous out;
  out.a.resize(0, 0);
  out.b.resize(0);
  out.c.resize(0);
  out.d = 1.0;
  for (std::size_t i = 0; i < section_poles.size(); ++i)
    out = series(out, make_section(section_poles[i], section_zeros[i]));
  out.poles = all_roots(poles);
  return out;
}

void refuse_unstable(const std::string& field, Complex p) {
  if (!std::isfinite(p.real()) || !std::isfinite(p.imag())) throw ParameterError(field, "pole is not finite");
  if (!(p.real() < 0.0)) {
    throw ParameterError(field, std::string(p.real() == 0.0 ? "marginally stable" : "unstable") +
                                    " pole at s = " + hz_text(p) + ": the stage must be stable (real part < 0)");
  }
}

void refuse_too_many_states(const std::string& field, int states) {
  if (states > LinearStageSpec::kMaxStates) {
    throw ParameterError(field, "the model has " + std::to_string(states) + " states, at most " +
                                    std::to_string(LinearStageSpec::kMaxStates) + " are supported");
  }
}

Continuous realise_zero_pole(const LinearStageSpec& spec) {
  std::vector<Factor> poles, zeros;
  int np = 0, nz = 0;
  for (std::size_t i = 0; i < spec.poles.size(); ++i) {
    const auto& r = spec.poles[i];
    const Complex s(kTwoPi * r.real_hz, kTwoPi * std::abs(r.imag_hz));
    refuse_unstable(index_field("stage.poles", i), s);
    poles.push_back({s, r.imag_hz != 0.0});
    np += poles.back().states();
  }
  for (std::size_t i = 0; i < spec.zeros.size(); ++i) {
    const auto& r = spec.zeros[i];
    const Complex s(kTwoPi * r.real_hz, kTwoPi * std::abs(r.imag_hz));
    if (!std::isfinite(s.real()) || !std::isfinite(s.imag())) {
      throw ParameterError(index_field("stage.zeros", i), "zero is not finite");
    }
    if (s == Complex(0.0, 0.0)) {
      throw ParameterError(index_field("stage.zeros", i), "a zero at s = 0 makes the DC gain zero");
    }
    zeros.push_back({s, r.imag_hz != 0.0});
    nz += zeros.back().states();
  }
  refuse_too_many_states("stage.poles", np);
  if (nz > np) {
    throw ParameterError("stage.zeros", "more zeros (" + std::to_string(nz) + ") than poles (" + std::to_string(np) +
                                            "): the model is improper");
  }
  return cascade(poles, zeros);
}

std::vector<double> strip_leading_zeros(const std::string& field, const std::vector<double>& p) {
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (!std::isfinite(p[i])) throw ParameterError(index_field(field, i), "must be a finite number");
  }
  std::size_t first = 0;
  while (first < p.size() && p[first] == 0.0) ++first;
  if (first == p.size()) throw ParameterError(field, "has no non-zero coefficient");
  return {p.begin() + static_cast<std::ptrdiff_t>(first), p.end()};
}

Continuous realise_transfer_function(const LinearStageSpec& spec) {
  const std::vector<double> num = strip_leading_zeros("stage.numerator_s", spec.numerator_s);
  const std::vector<double> den = strip_leading_zeros("stage.denominator_s", spec.denominator_s);
  const int nz = static_cast<int>(num.size()) - 1, np = static_cast<int>(den.size()) - 1;
  refuse_too_many_states("stage.denominator_s", np);
  if (nz > np) {
    throw ParameterError("stage.numerator_s", "degree " + std::to_string(nz) + " above the denominator's (" +
                                                  std::to_string(np) + "): the model is improper");
  }
  if (den.back() == 0.0) {
    throw ParameterError("stage.denominator_s", "marginally stable pole at s = 0 (constant coefficient 0)");
  }
  if (num.back() == 0.0) throw ParameterError("stage.numerator_s", "a zero at s = 0 makes the DC gain zero");
  const std::vector<Factor> poles = factors_of(polynomial_roots(den));
  for (const Factor& p : poles) refuse_unstable("stage.denominator_s", p.root);
  return cascade(poles, factors_of(polynomial_roots(num)));
}

Continuous realise_modes(const LinearStageSpec& spec) {
  const int n = 2 * static_cast<int>(spec.modes.size());
  refuse_too_many_states("stage.modes", n);
  double total = 0.0;
  for (std::size_t i = 0; i < spec.modes.size(); ++i) {
    const auto& m = spec.modes[i];
    const std::string field = index_field("stage.modes", i);
    require_positive(field + ".frequency_hz", m.frequency_hz);
    if (!std::isfinite(m.damping_ratio) || !(m.damping_ratio > 0.0)) {
      throw ParameterError(field + ".damping_ratio", "must be > 0 (got " + number_text(m.damping_ratio) +
                                                         "): a mode without damping is marginally stable");
    }
    require_finite(field + ".weight", m.weight);
    total += m.weight;
  }
  if (n == 0) throw ParameterError("stage.modes", "no mode given");
  if (!std::isfinite(total) || total == 0.0) {
    throw ParameterError("stage.modes", "the weights sum to " + number_text(total) + ": the DC gain must be non-zero");
  }
  Continuous out;
  out.a = Eigen::MatrixXd::Zero(n, n);
  out.b = Eigen::VectorXd::Zero(n);
  out.c = Eigen::RowVectorXd::Zero(n);
  out.d = 0.0;
  for (std::size_t i = 0; i < spec.modes.size(); ++i) {
    const auto& m = spec.modes[i];
    const double w = kTwoPi * m.frequency_hz, z = m.damping_ratio;
    const Eigen::Index j = 2 * static_cast<Eigen::Index>(i);
    out.a(j, j + 1) = w;  // [q, q' / w]
    out.a(j + 1, j) = -w;
    out.a(j + 1, j + 1) = -2.0 * z * w;
    out.b(j + 1) = w;
    out.c(j) = m.weight / total;
    const Complex root = std::sqrt(Complex(z * z - 1.0, 0.0));
    out.poles.push_back(w * (-z + root));
    out.poles.push_back(w * (-z - root));
  }
  return out;
}

Continuous realise(const LinearStageSpec& spec) {
  switch (spec.form) {
    case LinearStageSpec::Form::kZeroPoleGain: return realise_zero_pole(spec);
    case LinearStageSpec::Form::kTransferFunction: return realise_transfer_function(spec);
    case LinearStageSpec::Form::kModes: return realise_modes(spec);
    default: break;
  }
  throw ParameterError("stage.form", "must be zero_pole, transfer_function, modes or discrete");
}

// Ascending powers of z^-1 of prod (1 - r z^-1) (real: the roots come in conjugate pairs).
DiscreteLinearStage::Coefficients expand(const DiscreteLinearStage::Roots& roots) {
  std::vector<Complex> p{1.0};
  for (Eigen::Index i = 0; i < roots.size(); ++i) {
    std::vector<Complex> q(p.size() + 1, 0.0);
    for (std::size_t j = 0; j < p.size(); ++j) {
      q[j] += p[j];
      q[j + 1] -= roots(i) * p[j];
    }
    p = q;
  }
  DiscreteLinearStage::Coefficients out(static_cast<Eigen::Index>(p.size()));
  for (std::size_t j = 0; j < p.size(); ++j) out(static_cast<Eigen::Index>(j)) = p[j].real();
  return out;
}

DiscreteLinearStage::Roots eigenvalues(const Eigen::MatrixXd& m) {
  DiscreteLinearStage::Roots out(m.rows());
  if (m.rows() == 0) return out;
  const Eigen::EigenSolver<Eigen::MatrixXd> eig(m, false);
  for (Eigen::Index i = 0; i < m.rows(); ++i) out(i) = eig.eigenvalues()(i);
  return out;
}

struct SampledRational {  // x_{k+1} = A x_k + B v_k, y_k = C x_k + D v_k
  Eigen::MatrixXd a;
  Eigen::VectorXd b;
  Eigen::RowVectorXd c;
  double d = 0.0;
  DiscreteLinearStage::Roots poles;
  std::vector<double> numerator;  // given (form d), else empty
};

SampledRational sample(const Continuous& m, double dt_s, double fraction) {
  const Eigen::Index n = m.a.rows();
  Eigen::MatrixXd aug = Eigen::MatrixXd::Zero(n + 1, n + 1);
  aug.topLeftCorner(n, n) = m.a;
  aug.topRightCorner(n, 1) = m.b;
  const Eigen::MatrixXd late = (aug * ((1.0 - fraction) * dt_s)).exp();  // the last (1 - f) dt of the tick
  Eigen::MatrixXd phi = late.topLeftCorner(n, n);
  const Eigen::VectorXd gamma0 = late.topRightCorner(n, 1);
  SampledRational s;
  const Eigen::Index nd = n + (fraction > 0.0 ? 1 : 0);
  s.a = Eigen::MatrixXd::Zero(nd, nd);
  s.b = Eigen::VectorXd::Zero(nd);
  s.c = Eigen::RowVectorXd::Zero(nd);
  s.poles.resize(nd);
  for (Eigen::Index i = 0; i < n; ++i) s.poles(i) = std::exp(m.poles[static_cast<std::size_t>(i)] * dt_s);
  if (fraction > 0.0) {
    const Eigen::MatrixXd early = (aug * (fraction * dt_s)).exp();  // the first f dt: the previous input
    const Eigen::VectorXd gamma1 = phi * early.topRightCorner(n, 1);
    phi = phi * early.topLeftCorner(n, n);
    // State [x_k; v_{k-1}]: x_{k+1} = Phi x_k + Gamma1 v_{k-1} + Gamma0 v_k.
    s.a.topRightCorner(n, 1) = gamma1;
    s.b(n) = 1.0;
    s.c(n) = m.c.dot(gamma1);
    s.poles(n) = 0.0;
  }
  s.a.topLeftCorner(n, n) = phi;
  s.b.head(n) = gamma0;
  s.c.head(n) = m.c * phi;  // y_k = C x_{k+1} + D v_k
  s.d = m.c.dot(gamma0) + m.d;
  return s;
}

SampledRational realise_discrete(const LinearStageSpec& spec, double dt_s, int& delay_ticks) {
  if (!(std::abs(spec.discrete_dt_s - dt_s) <= 1e-9 * dt_s)) {
    throw ParameterError("stage.discrete_dt_s", "the model was sampled at " + number_text(spec.discrete_dt_s) +
                                                    " s, the tick is " + number_text(dt_s) + " s");
  }
  std::vector<double> num = spec.numerator_zinv, den = spec.denominator_zinv;
  for (std::size_t i = 0; i < num.size(); ++i) {
    if (!std::isfinite(num[i])) throw ParameterError(index_field("stage.numerator_zinv", i), "must be finite");
  }
  for (std::size_t i = 0; i < den.size(); ++i) {
    if (!std::isfinite(den[i])) throw ParameterError(index_field("stage.denominator_zinv", i), "must be finite");
  }
  if (den.empty() || den[0] == 0.0)
    throw ParameterError("stage.denominator_zinv", "its first coefficient must be non-zero");
  std::size_t lead = 0;
  while (lead < num.size() && num[lead] == 0.0) ++lead;
  if (lead == num.size()) throw ParameterError("stage.numerator_zinv", "has no non-zero coefficient");
  delay_ticks += static_cast<int>(lead);
  num.erase(num.begin(), num.begin() + static_cast<std::ptrdiff_t>(lead));
  while (num.size() > 1 && num.back() == 0.0) num.pop_back();
  while (den.size() > 1 && den.back() == 0.0) den.pop_back();
  const std::size_t n = std::max(num.size(), den.size()) - 1;
  refuse_too_many_states("stage.denominator_zinv", static_cast<int>(n));
  num.resize(n + 1, 0.0);
  den.resize(n + 1, 0.0);
  const double a0 = den[0];
  for (double& v : den) v /= a0;
  double num_dc = 0.0, den_dc = 0.0;
  for (std::size_t i = 0; i <= n; ++i) {
    num_dc += num[i];
    den_dc += den[i];
  }
  SampledRational s;
  const auto ni = static_cast<Eigen::Index>(n);
  s.a = Eigen::MatrixXd::Zero(ni, ni);
  for (Eigen::Index j = 0; j < ni; ++j) s.a(0, j) = -den[static_cast<std::size_t>(j) + 1];
  for (Eigen::Index i = 1; i < ni; ++i) s.a(i, i - 1) = 1.0;
  s.poles = eigenvalues(s.a);
  for (Eigen::Index i = 0; i < s.poles.size(); ++i) {
    if (!(std::abs(s.poles(i)) < 1.0)) {
      throw ParameterError("stage.denominator_zinv",
                           std::string(std::abs(s.poles(i)) == 1.0 ? "marginally stable" : "unstable") +
                               " pole at z = " + number_text(s.poles(i).real()) + " + " +
                               number_text(s.poles(i).imag()) + "i (|z| >= 1)");
    }
  }
  if (num_dc == 0.0 || !std::isfinite(num_dc / den_dc)) {
    throw ParameterError("stage.numerator_zinv", "the DC gain is zero (the coefficients sum to 0)");
  }
  const double g = den_dc / num_dc;
  for (double& v : num) v *= g;
  s.b = Eigen::VectorXd::Zero(ni);
  if (ni > 0) s.b(0) = 1.0;
  s.c = Eigen::RowVectorXd::Zero(ni);
  for (Eigen::Index j = 0; j < ni; ++j) {
    const auto u = static_cast<std::size_t>(j) + 1;
    s.c(j) = num[u] - num[0] * den[u];
  }
  s.d = num[0];
  s.numerator = num;
  return s;
}

}  // namespace

LinearStageSpec LinearStageSpec::second_order(double k, double c) {
  // k / (s^2 + c s + k): the poles of s^2 + c s + k, in Hz.
  LinearStageSpec s;
  s.form = Form::kTransferFunction;
  s.numerator_s = {k};
  s.denominator_s = {1.0, c, k};
  return s;
}

LinearStageSpec LinearStageSpec::zero_pole(std::vector<Root> zeros, std::vector<Root> poles, double delay_s) {
  LinearStageSpec s;
  s.form = Form::kZeroPoleGain;
  s.zeros = std::move(zeros);
  s.poles = std::move(poles);
  s.delay_s = delay_s;
  return s;
}

LinearStageSpec LinearStageSpec::transfer_function(std::vector<double> numerator_s, std::vector<double> denominator_s,
                                                   double delay_s) {
  LinearStageSpec s;
  s.form = Form::kTransferFunction;
  s.numerator_s = std::move(numerator_s);
  s.denominator_s = std::move(denominator_s);
  s.delay_s = delay_s;
  return s;
}

LinearStageSpec LinearStageSpec::sum_of_modes(std::vector<Mode> modes, double delay_s) {
  LinearStageSpec s;
  s.form = Form::kModes;
  s.modes = std::move(modes);
  s.delay_s = delay_s;
  return s;
}

LinearStageSpec LinearStageSpec::discrete(std::vector<double> numerator_zinv, std::vector<double> denominator_zinv,
                                          double dt_s, double delay_s) {
  LinearStageSpec s;
  s.form = Form::kDiscrete;
  s.numerator_zinv = std::move(numerator_zinv);
  s.denominator_zinv = std::move(denominator_zinv);
  s.discrete_dt_s = dt_s;
  s.delay_s = delay_s;
  return s;
}

void LinearStageSpec::validate(double dt_s) const { (void)discretise(*this, dt_s); }

int LinearStageSpec::order() const {
  if (form == Form::kDiscrete) {
    int ticks = 0;
    return static_cast<int>(realise_discrete(*this, discrete_dt_s, ticks).a.rows());
  }
  return static_cast<int>(realise(*this).a.rows());
}

std::complex<double> LinearStageSpec::frequency_response(double f_hz) const {
  require_finite("f_hz", f_hz);
  if (form == Form::kDiscrete) return discretise(*this, discrete_dt_s).frequency_response(f_hz);
  require_non_negative("stage.delay_s", delay_s);
  const Continuous m = realise(*this);
  const double w = kTwoPi * f_hz;
  const Eigen::Index n = m.a.rows();
  Complex g = m.d;
  if (n > 0) {
    const Eigen::MatrixXcd si = Complex(0.0, w) * Eigen::MatrixXcd::Identity(n, n) - m.a.cast<Complex>();
    const Eigen::VectorXcd x = si.partialPivLu().solve(m.b.cast<Complex>());
    g += (m.c.cast<Complex>() * x)(0);
  }
  return g * std::exp(Complex(0.0, -w * delay_s));
}

std::complex<double> DiscreteLinearStage::frequency_response(double f_hz) const noexcept {
  const Complex zinv = std::polar(1.0, -kTwoPi * f_hz * dt_s);
  Complex g = d;
  for (Eigen::Index i = 0; i < zeros.size(); ++i) g *= 1.0 - zeros(i) * zinv;
  for (Eigen::Index i = 0; i < poles.size(); ++i) g /= 1.0 - poles(i) * zinv;
  return g * std::pow(zinv, delay_ticks);
}

double DiscreteLinearStage::dc_gain() const noexcept { return numerator.sum() / denominator.sum(); }

DiscreteLinearStage discretise(const LinearStageSpec& spec, double dt_s) {
  require_in_range("dt_s", dt_s, 1e-7, 1.0);
  if (!std::isfinite(spec.delay_s) || spec.delay_s < 0.0 ||
      spec.delay_s > LinearStageSpec::kMaxDelayTicks * dt_s * (1.0 + 1e-12)) {
    throw ParameterError("stage.delay_s", "must be in [0, " + number_text(LinearStageSpec::kMaxDelayTicks * dt_s) +
                                              "] s, i.e. at most " + number_text(LinearStageSpec::kMaxDelayTicks) +
                                              " ticks of " + number_text(dt_s) + " s (got " +
                                              number_text(spec.delay_s) + ")");
  }
  // Whole ticks and the fraction; a fraction within 1e-9 tick of a whole number is that number.
  const double ticks = spec.delay_s / dt_s;
  int whole = static_cast<int>(std::floor(ticks));
  double fraction = ticks - whole;
  if (fraction < 1e-9) {
    fraction = 0.0;
  } else if (fraction > 1.0 - 1e-9) {
    fraction = 0.0;
    ++whole;
  }
  SampledRational s;
  if (spec.form == LinearStageSpec::Form::kDiscrete) {
    if (fraction != 0.0) {
      throw ParameterError("stage.delay_s", "a model sampled at the tick takes whole ticks of delay (got " +
                                                number_text(ticks) + " ticks)");
    }
    s = realise_discrete(spec, dt_s, whole);
    if (whole > DiscreteLinearStage::kMaxDelayTicks) {
      throw ParameterError("stage.delay_s", "with the numerator's leading zeros the delay is " + std::to_string(whole) +
                                                " ticks, at most " +
                                                std::to_string(DiscreteLinearStage::kMaxDelayTicks));
    }
  } else {
    s = sample(realise(spec), dt_s, fraction);
  }
  if (!(s.d != 0.0) || !std::isfinite(s.d)) {
    throw ParameterError("stage.delay_s", "the stage's response at the end of the first tick is " + number_text(s.d) +
                                              ", so its sampled model has a zero at infinity; round the delay to "
                                              "whole ticks or shift it by a hair");
  }
  DiscreteLinearStage out;
  out.dt_s = dt_s;
  out.delay_ticks = whole;
  out.a = s.a;
  out.b = s.b;
  out.c = s.c;
  out.d = s.d;
  out.poles = s.poles;
  out.zeros = eigenvalues(s.a - s.b * s.c / s.d);
  for (Eigen::Index i = 0; i < out.zeros.size(); ++i) {
    if (!std::isfinite(out.zeros(i).real()) || !std::isfinite(out.zeros(i).imag())) {
      throw ParameterError("stage.delay_s", "the sampled model has a zero at infinity; round the delay");
    }
  }
  DiscreteLinearStage::Coefficients rational(out.zeros.size() + 1);
  if (!s.numerator.empty()) {
    for (std::size_t i = 0; i < s.numerator.size(); ++i) rational(static_cast<Eigen::Index>(i)) = s.numerator[i];
  } else {
    rational = s.d * expand(out.zeros);
  }
  out.numerator = DiscreteLinearStage::Coefficients::Zero(rational.size() + whole);
  out.numerator.tail(rational.size()) = rational;
  out.denominator = expand(out.poles);
  return out;
}

LinearStageSimulator::LinearStageSimulator(const DiscreteLinearStage& stage) : stage_(stage) {
  const Eigen::Index n = stage_.a.rows();
  x_ = DiscreteLinearStage::Column::Zero(n);
  x_next_ = x_;
  // At rest: x = A x + B  =>  (I - A) x = B (I - A is regular: every pole is inside the unit circle).
  const Eigen::MatrixXd i_minus_a = Eigen::MatrixXd::Identity(n, n) - Eigen::MatrixXd(stage_.a);
  x_rest_ = n > 0 ? DiscreteLinearStage::Column(i_minus_a.partialPivLu().solve(Eigen::VectorXd(stage_.b))) : x_;
  reset(0.0);
}

void LinearStageSimulator::reset(double y0) noexcept {
  x_ = x_rest_ * y0;
  delayed_.fill(y0);
  head_ = 0;
}

double LinearStageSimulator::step(double w) noexcept {
  if (!std::isfinite(w)) return std::numeric_limits<double>::quiet_NaN();
  double v = w;
  if (stage_.delay_ticks > 0) {
    v = delayed_[static_cast<std::size_t>(head_)];  // w_{k-d}
    delayed_[static_cast<std::size_t>(head_)] = w;
    head_ = head_ + 1 == stage_.delay_ticks ? 0 : head_ + 1;
  }
  const double y = stage_.c.dot(x_) + stage_.d * v;
  x_next_.noalias() = stage_.a * x_;
  x_next_ += stage_.b * v;
  x_.swap(x_next_);
  return y;
}

}  // namespace hystloop
