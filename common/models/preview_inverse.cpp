#include "models/preview_inverse.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>
#include <string>
#include <vector>

#include "core/errors.hpp"

namespace hystloop {
namespace {

using Complex = std::complex<double>;

std::string z_text(Complex z) {
  return number_text(z.real()) + (z.imag() < 0 ? " - " : " + ") + number_text(std::abs(z.imag())) + "i";
}

// The l1 norm of E = 1 - Q H_L (Q = 1 + q_1 z + .. + q_m z^m, H_L the series of 1/Q cut after z^L):
// its taps are at z^{L+1} .. z^{L+m}.
double truncation_norm(const std::vector<double>& q, const std::vector<double>& h, int taps) {
  const int m = static_cast<int>(q.size()) - 1;
  const int last = taps - 1;
  double norm = 0.0;
  for (int p = last + 1; p <= last + m; ++p) {
    double e = 0.0;
    for (int i = p - last; i <= std::min(m, p); ++i)
      e += q[static_cast<std::size_t>(i)] * h[static_cast<std::size_t>(p - i)];
    norm += std::abs(e);
  }
  return norm;
}

}  // namespace

PreviewStageInverse::PreviewStageInverse(const DiscreteLinearStage& stage, std::int64_t preview_ticks,
                                         double reference_bandwidth_hz)
    : stage_(stage), preview_(preview_ticks), bandwidth_hz_(reference_bandwidth_hz) {
  if (preview_ticks < 0 || preview_ticks > kMaxPreviewTicks) {
    throw ParameterError("preview_ticks", "must be in [0, " + std::to_string(kMaxPreviewTicks) + "] (got " +
                                              std::to_string(preview_ticks) + ")");
  }
  // Split the zeros: inside -> causal sections, outside -> the anti-causal series.
  std::vector<Complex> out, inside;
  for (Eigen::Index i = 0; i < stage_.zeros.size(); ++i) {
    const Complex z = stage_.zeros(i);
    const double r = std::abs(z);
    if (std::abs(r - 1.0) <= kMinZeroDistance) {
      const double f = std::abs(std::arg(z)) / (2.0 * std::numbers::pi * stage_.dt_s);
      throw ParameterError("stage", "has a zero on the unit circle, z = " + z_text(z) + " (|z| = " + number_text(r, 9) +
                                        "): it does not pass " + number_text(f) +
                                        " Hz and no inverse can restore that");
    }
    if (r < 1.0) {
      if (z.imag() >= 0.0) inside.push_back(z);  // a conjugate pair once
    } else {
      out.push_back(z);
    }
  }
  std::vector<Complex> poles;
  for (Eigen::Index i = 0; i < stage_.poles.size(); ++i) {
    if (stage_.poles(i).imag() >= 0.0) poles.push_back(stage_.poles(i));
  }
  // Second-order sections: each inside zero (the inverse's pole) with the stage's pole nearest to
  // it (the inverse's zero), those nearest the unit circle first, so that no section's output is
  // a tiny difference of large numbers (a 16th-order polynomial of poles near the unit circle as
  // one FIR loses about six digits).
  std::sort(inside.begin(), inside.end(), [](Complex a, Complex b) { return std::abs(a) > std::abs(b); });
  std::vector<bool> used(poles.size(), false);
  auto factor = [](Complex root, double& c1, double& c2) {
    c1 = root.imag() == 0.0 ? -root.real() : -2.0 * root.real();
    c2 = root.imag() == 0.0 ? 0.0 : std::norm(root);
  };
  for (const Complex z : inside) {
    Section sec;
    factor(z, sec.a1, sec.a2);
    std::size_t best = poles.size();
    for (std::size_t j = 0; j < poles.size(); ++j) {
      if (used[j] || (poles[j].imag() == 0.0) != (z.imag() == 0.0)) continue;  // same order
      if (best == poles.size() || std::abs(poles[j] - z) < std::abs(poles[best] - z)) best = j;
    }
    if (best < poles.size()) {
      used[best] = true;
      factor(poles[best], sec.b1, sec.b2);
    }
    section_[static_cast<std::size_t>(sections_++)] = sec;
  }
  for (std::size_t j = 0; j < poles.size(); ++j) {
    if (used[j]) continue;
    Section sec;
    factor(poles[j], sec.b1, sec.b2);
    section_[static_cast<std::size_t>(sections_++)] = sec;
  }
  outside_ = static_cast<int>(out.size());
  lead_ = stage_.delay_ticks + outside_;
  // The low-pass: a Blackman-windowed sinc, g_j = 2 fc dt sinc(2 fc dt j) w(j), |j| <= M, sum 1.
  if (reference_bandwidth_hz != 0.0) {
    const double lowest = 4.0 / (kMaxLowPassHalfLength * stage_.dt_s), nyquist = 0.5 / stage_.dt_s;
    if (!std::isfinite(reference_bandwidth_hz) || reference_bandwidth_hz < lowest ||
        reference_bandwidth_hz >= nyquist) {
      throw ParameterError("reference_bandwidth_hz", "must be 0 (off) or in [" + number_text(lowest) + ", " +
                                                         number_text(nyquist) + ") Hz (got " +
                                                         number_text(reference_bandwidth_hz) + ")");
    }
    half_ = static_cast<int>(std::ceil(4.0 / (reference_bandwidth_hz * stage_.dt_s) - 1e-9));
  }
  const double fc = reference_bandwidth_hz * stage_.dt_s;  // cycles per tick
  double gsum = 0.0;
  for (int j = 0; j <= half_; ++j) {  // symmetric to the last bit: zero phase
    double g = 1.0;
    if (half_ > 0) {
      const double x = 2.0 * std::numbers::pi * fc * j;
      const double sinc = j == 0 ? 1.0 : std::sin(x) / x;
      const double phase = std::numbers::pi * j / half_;  // the Blackman window centred on 0
      g = 2.0 * fc * sinc * (0.42 + 0.5 * std::cos(phase) + 0.08 * std::cos(2.0 * phase));
    }
    const auto centre = static_cast<std::size_t>(half_), offset = static_cast<std::size_t>(j);
    lowpass_[centre + offset] = g;
    lowpass_[centre - offset] = g;
    gsum += j == 0 ? g : 2.0 * g;
  }
  for (int j = 0; j <= 2 * half_; ++j) lowpass_[static_cast<std::size_t>(j)] /= gsum;
  if (preview_ticks < lead_ + half_) {
    throw ParameterError("preview_ticks", "must be at least " + std::to_string(lead_ + half_) + " ticks (" +
                                              std::to_string(stage_.delay_ticks) + " of delay, one per zero outside " +
                                              "the unit circle and " + std::to_string(half_) +
                                              " for the reference's low-pass), got " + std::to_string(preview_ticks));
  }
  // Q(z) = prod_o (1 - z / z_o), real; scale 1 / (K prod_o (-z_o)).
  std::vector<Complex> qc{1.0};
  Complex prod = 1.0;
  for (const Complex z : out) {
    std::vector<Complex> next(qc.size() + 1, 0.0);
    for (std::size_t j = 0; j < qc.size(); ++j) {
      next[j] += qc[j];
      next[j + 1] -= qc[j] / z;
    }
    qc = next;
    prod *= -z;
  }
  scale_ = 1.0 / (stage_.d * prod.real());
  std::vector<double> q(qc.size());
  for (std::size_t j = 0; j < qc.size(); ++j) q[j] = qc[j].real();
  // h_j, the series of 1 / Q: h_0 = 1, h_j = -sum_i q_i h_{j-i}.
  const int max_taps = static_cast<int>(preview_ticks) - lead_ - half_ + 1;
  const int m = outside_;
  std::vector<double> h{1.0};
  h.resize(static_cast<std::size_t>(max_taps) + static_cast<std::size_t>(m), 0.0);
  for (int j = 1; j < max_taps + m; ++j) {
    double v = 0.0;
    for (int i = 1; i <= std::min(j, m); ++i) v -= q[static_cast<std::size_t>(i)] * h[static_cast<std::size_t>(j - i)];
    h[static_cast<std::size_t>(j)] = v;
  }
  // As few taps as bring the bound to 1e-17, at most the preview allows.
  taps_ = max_taps;
  for (int t = 1; t <= max_taps; ++t) {
    if (truncation_norm(q, h, t) <= 1e-17) {
      taps_ = t;
      break;
    }
  }
  double lowpass_l1 = 0.0;
  for (int j = 0; j <= 2 * half_; ++j) lowpass_l1 += std::abs(lowpass_[static_cast<std::size_t>(j)]);
  bound_ = truncation_norm(q, h, taps_) * lowpass_l1;
  if (bound_ > kMaxTruncationError) {
    double rho = 0.0;
    for (const Complex z : out) rho = std::max(rho, 1.0 / std::abs(z));
    const double needed = lead_ + half_ + std::ceil(std::log(kMaxTruncationError) / std::log(rho)) + 1.0;
    throw ParameterError("preview_ticks",
                         std::to_string(preview_ticks) + " ticks leave a truncation error bound of " +
                             number_text(bound_) + " (> " + number_text(kMaxTruncationError) +
                             "): the zero(s) outside the unit circle, the closest at |z| = " + number_text(1.0 / rho) +
                             ", need about " + number_text(needed) + " ticks of preview");
  }
  // c = h * g: c_i multiplies r_{k+lead-M+i}, i = 0 .. taps - 1 + 2M.
  c_taps_ = taps_ + 2 * half_;
  for (int i = 0; i < c_taps_; ++i) {
    double v = 0.0;
    for (int j = std::max(0, i - 2 * half_); j <= std::min(taps_ - 1, i); ++j) {
      v += h[static_cast<std::size_t>(j)] * lowpass_[static_cast<std::size_t>(i - j)];
    }
    c_[static_cast<std::size_t>(i)] = v;
  }
  ring_ = static_cast<std::size_t>(preview_ticks + half_) + 1;
  reset(0.0);
}

void PreviewStageInverse::reset(double y0) noexcept {
  const std::size_t n = ring_;
  for (std::size_t i = 0; i < n; ++i) r_[i] = y0;
  head_ = n - 1;
  double s = 0.0;
  for (int j = 0; j < c_taps_; ++j) s += c_[static_cast<std::size_t>(j)];
  s *= y0;
  double t = s;
  for (int i = 0; i < sections_; ++i) {
    Section& sec = section_[static_cast<std::size_t>(i)];
    sec.x1 = t;
    sec.x2 = t;
    t *= (1.0 + sec.b1 + sec.b2) / (1.0 + sec.a1 + sec.a2);
    sec.u1 = t;
    sec.u2 = t;
  }
  w_prev_ = scale_ * t;
}

double PreviewStageInverse::step(double r_future) noexcept {
  if (!std::isfinite(r_future)) return w_prev_;
  const std::size_t n = ring_;
  head_ = head_ + 1 == n ? 0 : head_ + 1;
  r_[head_] = r_future;  // r_{k+N}
  // s_k = sum_i c_i r_{k+lead-M+i}; r_{k+t} sits (N - t) places before the head.
  std::size_t idx = head_ + n - static_cast<std::size_t>(preview_ - lead_ + half_);
  if (idx >= n) idx -= n;
  double s = 0.0;
  for (int j = 0; j < c_taps_; ++j) {
    s += c_[static_cast<std::size_t>(j)] * r_[idx];
    idx = idx + 1 == n ? 0 : idx + 1;
  }
  // The stage's poles (FIR) and inside zeros (IIR, causal), section by section.
  double t = s;
  for (int i = 0; i < sections_; ++i) {
    Section& sec = section_[static_cast<std::size_t>(i)];
    const double u = t + sec.b1 * sec.x1 + sec.b2 * sec.x2 - sec.a1 * sec.u1 - sec.a2 * sec.u2;
    sec.x2 = sec.x1;
    sec.x1 = t;
    sec.u2 = sec.u1;
    sec.u1 = u;
    t = u;
  }
  w_prev_ = scale_ * t;
  return w_prev_;
}

double PreviewStageInverse::gain(double f_hz) const noexcept { return 1.0 / std::abs(stage_.frequency_response(f_hz)); }

}  // namespace hystloop
