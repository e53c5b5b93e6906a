#include "models/katalenic_shaping.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "core/errors.hpp"

namespace hystloop {
namespace {

using Coefficients = std::array<double, ShapingFunction::kMaxCoefficients>;

std::size_t degree_of(const Coefficients& c) {
  std::size_t n = c.size() - 1;
  while (n > 0 && c[n] == 0.0) --n;
  return n;
}

// p(x) and p'(x) together by Horner's scheme.
void horner(const Coefficients& c, double x, double& p, double& dp) noexcept {
  p = c[c.size() - 1];
  dp = 0.0;
  for (std::size_t i = c.size() - 1; i-- > 0;) {
    dp = dp * x + p;
    p = p * x + c[i];
  }
}

double horner_second(const Coefficients& c, double x) noexcept {
  double d2 = 0.0;
  for (std::size_t i = c.size() - 1; i >= 2; --i) {
    d2 = d2 * x + static_cast<double>(i * (i - 1)) * c[i];
  }
  return d2;
}

double binomial(std::size_t n, std::size_t k) {
  double r = 1.0;
  for (std::size_t i = 1; i <= k; ++i) r = r * static_cast<double>(n - k + i) / static_cast<double>(i);
  return r;
}

// Bernstein coefficients of p' on [a, b]. Their minimum bounds p' from below, their maximum from
// above, and the end coefficients are the end values: this turns "p' > 0 on [a, b]" into a proof.
std::vector<double> derivative_bernstein(const Coefficients& c, double a, double b) {
  const std::size_t deg = degree_of(c);
  if (deg == 0) return {0.0};
  const std::size_t n = deg - 1;  // degree of p'
  std::vector<double> d(n + 1);
  for (std::size_t j = 0; j <= n; ++j) d[j] = static_cast<double>(j + 1) * c[j + 1];
  // q(t) = p'(a + h t): Taylor shift, then scale.
  const double h = b - a;
  std::vector<double> q(n + 1, 0.0);
  for (std::size_t k = 0; k <= n; ++k) {
    double s = 0.0;
    for (std::size_t j = k; j <= n; ++j) s += d[j] * binomial(j, k) * std::pow(a, static_cast<double>(j - k));
    q[k] = s * std::pow(h, static_cast<double>(k));
  }
  std::vector<double> bern(n + 1, 0.0);
  for (std::size_t i = 0; i <= n; ++i) {
    for (std::size_t k = 0; k <= i; ++k) bern[i] += binomial(i, k) / binomial(n, k) * q[k];
  }
  return bern;
}

void split_half(const std::vector<double>& b, std::vector<double>& left, std::vector<double>& right) {
  const std::size_t n = b.size() - 1;
  std::vector<double> w = b;
  left.assign(n + 1, 0.0);
  right.assign(n + 1, 0.0);
  left[0] = w[0];
  right[n] = w[n];
  for (std::size_t r = 1; r <= n; ++r) {
    for (std::size_t i = 0; i + r <= n; ++i) w[i] = 0.5 * (w[i] + w[i + 1]);
    left[r] = w[0];
    right[n - r] = w[n - r];
  }
}

// True when p' > 0 is proven on [a, b]; otherwise `where` is a point with p' <= 0 (or undecided).
bool prove_positive(const std::vector<double>& b, double a, double w, int depth, double& where) {
  if (*std::min_element(b.begin(), b.end()) > 0.0) return true;
  if (b.front() <= 0.0) {
    where = a;
    return false;
  }
  if (b.back() <= 0.0) {
    where = a + w;
    return false;
  }
  if (depth >= 48) {
    where = a + 0.5 * w;
    return false;
  }
  std::vector<double> left, right;
  split_half(b, left, right);
  return prove_positive(left, a, 0.5 * w, depth + 1, where) &&
         prove_positive(right, a + 0.5 * w, 0.5 * w, depth + 1, where);
}

double max_bernstein(const std::vector<double>& b, int depth) {
  if (depth == 0) return *std::max_element(b.begin(), b.end());
  std::vector<double> left, right;
  split_half(b, left, right);
  return std::max(max_bernstein(left, depth - 1), max_bernstein(right, depth - 1));
}

std::string field_of(std::string_view field, const char* member) { return std::string(field) + "." + member; }

}  // namespace

ShapingFunction ShapingFunction::make_linear(double gain, double offset) {
  ShapingFunction s;
  s.kind = ShapingKind::linear;
  s.gain = gain;
  s.offset = offset;
  return s;
}

ShapingFunction ShapingFunction::make_polynomial(std::initializer_list<double> coefficients, double domain_min,
                                                 double domain_max) {
  if (coefficients.size() > kMaxCoefficients) {
    throw ParameterError("coefficients", "at most " + std::to_string(kMaxCoefficients) + " (degree 7)");
  }
  ShapingFunction s;
  s.kind = ShapingKind::polynomial;
  std::copy(coefficients.begin(), coefficients.end(), s.coefficients.begin());
  s.domain_min = domain_min;
  s.domain_max = domain_max;
  return s;
}

ShapingFunction ShapingFunction::make_odd_polynomial(std::initializer_list<double> odd_coefficients, double domain_min,
                                                     double domain_max) {
  if (odd_coefficients.size() > kMaxCoefficients / 2) {
    throw ParameterError("coefficients", "at most 4 odd coefficients (degree 7)");
  }
  ShapingFunction s;
  s.kind = ShapingKind::polynomial;
  std::size_t i = 1;
  for (double c : odd_coefficients) {
    s.coefficients[i] = c;
    i += 2;
  }
  s.domain_min = domain_min;
  s.domain_max = domain_max;
  return s;
}

ShapingFunction ShapingFunction::make_tanh(double amplitude, double scale, double offset) {
  ShapingFunction s;
  s.kind = ShapingKind::tanh;
  s.amplitude = amplitude;
  s.scale = scale;
  s.offset = offset;
  return s;
}

void ShapingFunction::validate(std::string_view field) const {
  switch (kind) {
    case ShapingKind::linear:
      require_positive(field_of(field, "gain"), gain);
      require_finite(field_of(field, "offset"), offset);
      return;
    case ShapingKind::tanh:
      require_positive(field_of(field, "amplitude"), amplitude);
      require_positive(field_of(field, "scale"), scale);
      require_finite(field_of(field, "offset"), offset);
      return;
    case ShapingKind::polynomial: {
      for (std::size_t i = 0; i < coefficients.size(); ++i) {
        require_finite(field_of(field, "coefficients") + "[" + std::to_string(i) + "]", coefficients[i]);
      }
      require_finite(field_of(field, "domain_min"), domain_min);
      require_finite(field_of(field, "domain_max"), domain_max);
      if (!(domain_min < domain_max)) {
        throw ParameterError(field_of(field, "domain_max"), "must be > domain_min");
      }
      double where = 0.0;
      const auto bern = derivative_bernstein(coefficients, domain_min, domain_max);
      if (!prove_positive(bern, domain_min, domain_max - domain_min, 0, where)) {
        std::ostringstream os;
        os << "polynomial is not strictly increasing on [" << domain_min << ", " << domain_max
           << "] (derivative <= 0 near x = " << where << ")";
        throw ParameterError(field_of(field, "coefficients"), os.str());
      }
      return;
    }
  }
  throw ParameterError(field_of(field, "kind"), "unknown shaping kind");
}

double ShapingFunction::apply(double x) const noexcept {
  switch (kind) {
    case ShapingKind::linear: return gain * x + offset;
    case ShapingKind::tanh: return offset + amplitude * std::tanh(x / scale);
    case ShapingKind::polynomial: {
      const double xc = std::clamp(x, domain_min, domain_max);
      double p = 0.0, dp = 0.0;
      horner(coefficients, xc, p, dp);
      return p + dp * (x - xc);  // end tangent outside the domain
    }
  }
  return x;
}

double ShapingFunction::derivative(double x) const noexcept {
  switch (kind) {
    case ShapingKind::linear: return gain;
    case ShapingKind::tanh: {
      const double t = std::tanh(x / scale);
      return amplitude / scale * (1.0 - t * t);
    }
    case ShapingKind::polynomial: {
      double p = 0.0, dp = 0.0;
      horner(coefficients, std::clamp(x, domain_min, domain_max), p, dp);
      return dp;
    }
  }
  return 1.0;
}

double ShapingFunction::second_derivative(double x) const noexcept {
  switch (kind) {
    case ShapingKind::linear: return 0.0;
    case ShapingKind::tanh: {
      const double t = std::tanh(x / scale);
      return -2.0 * amplitude / (scale * scale) * t * (1.0 - t * t);
    }
    case ShapingKind::polynomial: return (x < domain_min || x > domain_max) ? 0.0 : horner_second(coefficients, x);
  }
  return 0.0;
}

double ShapingFunction::invert(double y, double hint) const noexcept {
  switch (kind) {
    case ShapingKind::linear: return (y - offset) / gain;
    case ShapingKind::tanh: {
      constexpr double kLimit = 1.0 - 1e-12;
      const double r = std::clamp((y - offset) / amplitude, -kLimit, kLimit);
      return scale * std::atanh(r);
    }
    case ShapingKind::polynomial: break;
  }
  double pa = 0.0, da = 0.0, pb = 0.0, db = 0.0;
  horner(coefficients, domain_min, pa, da);
  horner(coefficients, domain_max, pb, db);
  if (y <= pa) return domain_min + (y - pa) / da;
  if (y >= pb) return domain_max + (y - pb) / db;
  // Safeguarded Newton: p is strictly increasing on the bracket, so a Newton step that leaves
  // [lo, hi] is replaced by bisection; the iteration count is bounded for the real-time path.
  const double tol =
      4.0 * std::numeric_limits<double>::epsilon() * std::max({std::abs(domain_min), std::abs(domain_max), 1e-300});
  double lo = domain_min, hi = domain_max;
  double x = std::isfinite(hint) ? std::clamp(hint, lo, hi) : 0.5 * (lo + hi);
  for (int it = 0; it < 100; ++it) {
    double p = 0.0, dp = 0.0;
    horner(coefficients, x, p, dp);
    const double f = p - y;
    if (f == 0.0) return x;
    (f < 0.0 ? lo : hi) = x;
    double next = x - f / dp;
    if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
    if (std::abs(next - x) <= tol || hi - lo <= tol) return next;
    x = next;
  }
  return x;
}

double ShapingFunction::max_slope() const noexcept {
  switch (kind) {
    case ShapingKind::linear: return gain;
    case ShapingKind::tanh: return amplitude / scale;
    case ShapingKind::polynomial: break;
  }
  try {
    return max_bernstein(derivative_bernstein(coefficients, domain_min, domain_max), 6);
  } catch (...) {
    return std::numeric_limits<double>::infinity();
  }
}

}  // namespace hystloop
