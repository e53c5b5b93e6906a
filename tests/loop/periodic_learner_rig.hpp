#pragma once
// What periodic_learner_test drives the PeriodicLearner with: the loop as the compensator runs it
// (the plan horizon_ticks ahead of the last sample, samples arriving in blocks), a linear plant
// from the corrected reference to the position, and the learning predicted per harmonic of the
// period, for the tests' bounds.
//
// For a plant y_k = g u_{k-d} + dist_k with u = r + c and T(w) = g e^{-jwd}, c_p the table learned
// from period p and applied in period p + L, e_p = E0 - T c_{p-L}, the tables follow
//   plain:            c_p = Q (c_{p-L} + gain e_p)                       (L chains)
//   lag-compensated:  c_p = Q ((1 - gain) c_{p-1} + gain (c_{p-L} + e_p))
// per harmonic; both have the fixed point error E = E0 (1 - Q) / (1 - Q + gain Q T). predict()
// runs these recursions from c = 0 for the error of every period (as the loop runs them: it takes
// each table into use exactly L periods after the one it was learned from, and Q is linear until
// the clamp), finds the largest root of their characteristic polynomials (the rate per period),
// and, for white sensor noise sigma (which enters as e_p - n_p), the stationary variance of the
// table from the recursion's impulse response.

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdint>
#include <functional>
#include <limits>
#include <numbers>
#include <random>
#include <utility>
#include <vector>

#include "loop/periodic_learner.hpp"

namespace hystloop::testing {

inline constexpr double kLearnDt = 1e-4;

// The learner with its tables adopted in one step at the boundary (blend_s = 0): the tables in
// use are then exactly what the update's recursion says, which is what these tests check. The
// deployed blend is tested on its own (PeriodicLearner.ANewTableTakesOverAlongTheBlend).
// The monitor is off: these tests check the update's own recursion, whatever it does (the monitor,
// which ends a line's learning when it makes the error worse, is tested in learning_monitor_test).
inline LearningConfig stepwise() {
  LearningConfig c;
  c.blend_s = 0.0;
  c.ramp_periods = 0.0;
  c.monitor_ratio = 0.0;
  return c;
}
inline constexpr std::int64_t kHorizon = 500;
inline constexpr std::int64_t kBlock = 20;
inline constexpr std::int64_t kMaxLag = kHorizon + kBlock;

// Q at f cycles per tick for half-width m (also the exact DFT of the circular window).
inline double triangle_response(double f, std::int64_t m) {
  const double x = std::numbers::pi * f;
  const double md = static_cast<double>(m);
  if (std::abs(std::sin(x)) < 1e-12) return 1.0;
  const double a = std::sin(md * x) / (md * std::sin(x));
  return a * a;
}

struct LinearPlant {
  double gain = 1.0;
  std::int64_t delay = 0;
  std::complex<double> at(double f) const {  // T at f cycles per tick
    return gain * std::polar(1.0, -2.0 * std::numbers::pi * f * static_cast<double>(delay));
  }
};

// The tests' periodic reference (a raster line's first and third harmonics) and a disturbance
// that repeats with it (its fifth harmonic and an offset), n ticks per period.
inline double raster(std::int64_t k, std::int64_t n, double a1) {
  const double x = 2.0 * std::numbers::pi * static_cast<double>(k) / static_cast<double>(n);
  return a1 * std::sin(x) + 0.2 * a1 * std::sin(3.0 * x + 0.4);
}
inline double disturbance(std::int64_t k, std::int64_t n) {
  return 30e-9 * std::sin(2.0 * std::numbers::pi * 5.0 * static_cast<double>(k) / static_cast<double>(n) + 1.0) + 20e-9;
}
// One period of the error without learning, in the steady state.
inline std::vector<double> error_without_learning(std::int64_t n, double a1, const LinearPlant& p) {
  std::vector<double> e(static_cast<std::size_t>(n));
  for (std::int64_t k = 0; k < n; ++k) {
    e[static_cast<std::size_t>(k)] = raster(k, n, a1) - p.gain * raster(k - p.delay, n, a1) - disturbance(k, n);
  }
  return e;
}

// The largest root's modulus of z^L - a z^(L-1) - b (Durand-Kerner; L is at most a few dozen).
inline double largest_root(std::int64_t l, double a, std::complex<double> b) {
  using C = std::complex<double>;
  if (l == 1) return std::abs(a + b);
  const auto n = static_cast<std::size_t>(l);
  std::vector<C> z(n);
  for (std::size_t i = 0; i < n; ++i) z[i] = std::pow(C(0.4, 0.9), static_cast<double>(i));
  auto poly = [&](C x) {
    const C xd = std::pow(x, static_cast<double>(l - 1));
    return xd * x - a * xd - b;
  };
  for (int it = 0; it < 5000; ++it) {
    double moved = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
      C den = 1.0;
      for (std::size_t j = 0; j < n; ++j) {
        if (j != i) den *= z[i] - z[j];
      }
      const C step = poly(z[i]) / den;
      z[i] -= step;
      moved = std::max(moved, std::abs(step));
    }
    if (moved < 1e-15) break;
  }
  double r = 0.0;
  for (const C& x : z) r = std::max(r, std::abs(x));
  return r;
}

// The learning's rate per period at one harmonic: the largest root of the tables' recursion.
inline double rate_per_period(bool lag_compensated, std::int64_t chain, double q, double gain, std::complex<double> t) {
  if (!lag_compensated) return std::pow(q * std::abs(1.0 - gain * t), 1.0 / static_cast<double>(chain));
  return largest_root(chain, q * (1.0 - gain), q * gain * (1.0 - t));
}

// How the learner runs: its update, and L, how many periods after the one it was learned from a
// table is taken into use (1 without lag; LearningLoop::first_adoption_period()).
struct Learning {
  bool lag_compensated = true;
  std::int64_t chain = 1;
  int periods = 0;  // how many periods of the error to predict
};

// The learning's predictions over one period of the error without learning, e0.
struct Prediction {
  double e0_rms = 0.0;
  double steady_rms = 0.0;        // the fixed point's error
  double noise_rms = 0.0;         // of the true error due to the noise learned (T times it)
  double correction_var = 0.0;    // of the learned signal under the noise alone (inf: not stationary)
  double rate = 0.0;              // the update's largest root per period over the harmonics (< 1: stable)
  double rate_e0 = 0.0;           // the same over the harmonics e0 has
  std::vector<double> error_rms;  // the error's RMS in periods 0 .. periods - 1, noise aside
};

inline Prediction predict(const std::vector<double>& e0, std::int64_t m, double gain, const LinearPlant& plant,
                          double sigma, const Learning& learning = {}) {
  using C = std::complex<double>;
  const auto n = e0.size();
  const double nd = static_cast<double>(n);
  const std::int64_t mm = std::min<std::int64_t>(m, static_cast<std::int64_t>(n));
  const auto chain = static_cast<std::size_t>(learning.chain);
  const auto periods = static_cast<std::size_t>(learning.periods);
  Prediction p;
  p.error_rms.assign(periods, 0.0);
  std::vector<C> tables(periods);  // c_p of one harmonic
  std::vector<C> impulse(chain);   // the last L tables' response to one period's noise
  double e0_sq = 0.0, steady_sq = 0.0, e0_max = 0.0;
  std::vector<std::complex<double>> spectrum(n);
  for (std::size_t h = 0; h < n; ++h) {
    std::complex<double> s = 0.0;
    for (std::size_t k = 0; k < n; ++k) {
      s += e0[k] * std::polar(1.0, -2.0 * std::numbers::pi * static_cast<double>(h * k % n) / nd);
    }
    spectrum[h] = s;
    e0_max = std::max(e0_max, std::abs(s));
  }
  for (std::size_t h = 0; h < n; ++h) {
    const double f = static_cast<double>(h) / nd;
    const double q = triangle_response(f, mm);
    const std::complex<double> t = plant.at(f);
    const std::complex<double> e = spectrum[h] * (1.0 - q) / (1.0 - q + gain * q * t);
    e0_sq += std::norm(spectrum[h]);
    steady_sq += std::norm(e);
    const double loop = q * std::abs(1.0 - gain * t);  // the plain update's, per step of L periods
    const double rate = rate_per_period(learning.lag_compensated, learning.chain, q, gain, t);
    p.rate = std::max(p.rate, rate);
    if (std::abs(spectrum[h]) > 1e-3 * e0_max) p.rate_e0 = std::max(p.rate_e0, rate);

    // The tables from zero, period by period, and the error each period sees.
    for (std::size_t k = 0; k < periods; ++k) {
      const C applied = k >= chain ? tables[k - chain] : C(0.0);
      const C err = spectrum[h] - t * applied;
      p.error_rms[k] += std::norm(err);
      const C newest = k >= 1 ? tables[k - 1] : C(0.0);
      tables[k] =
          learning.lag_compensated ? q * ((1.0 - gain) * newest + gain * (applied + err)) : q * (applied + gain * err);
    }

    // The noise: sigma^2 times the energy of the tables' response to a unit noise in one period.
    double energy = 0.0;
    if (!learning.lag_compensated) {
      energy = loop < 1.0 ? gain * gain * q * q / (1.0 - loop * loop) : std::numeric_limits<double>::infinity();
    } else if (rate >= 1.0) {
      energy = std::numeric_limits<double>::infinity();
    } else {
      std::fill(impulse.begin(), impulse.end(), C(0.0));
      C newest = -q * gain;  // c_0; impulse[k % L] holds c_{k-L} until c_k replaces it
      energy = std::norm(newest);
      impulse[0] = newest;
      for (std::size_t k = 1; k < 1000000; ++k) {
        const C old = impulse[k % chain];
        const C c = k >= chain ? q * ((1.0 - gain) * newest + gain * (1.0 - t) * old) : q * (1.0 - gain) * newest;
        impulse[k % chain] = c;
        newest = c;
        energy += std::norm(c);
        if (k > 4 * chain && std::norm(c) < 1e-16 * energy) {
          double tail = 0.0;
          for (const C& v : impulse) tail = std::max(tail, std::norm(v));
          if (tail < 1e-16 * energy) break;
        }
      }
    }
    const double var = energy * sigma * sigma;
    p.correction_var += var / nd;
    p.noise_rms += std::norm(t) * var / nd;
  }
  p.e0_rms = std::sqrt(e0_sq) / nd;  // Parseval: sum |e_k|^2 = sum |E_h|^2 / n
  p.steady_rms = std::sqrt(steady_sq) / nd;
  p.noise_rms = std::sqrt(p.noise_rms);
  for (double& e : p.error_rms) e = std::sqrt(e) / nd;
  return p;
}

// The closed loop: at bridge tick j the command planned for j is applied, the plant moves, the
// sensor adds white noise; every block ticks the samples go to observe() and the plan extends to
// the last sample + horizon. Everything is allocated in the constructor (the allocation test
// runs it inside its counter).
struct LearningLoop {
  using Reference = std::function<double(std::int64_t)>;
  using Disturbance = std::function<double(std::int64_t)>;

  LearningLoop(PeriodicLearner& l, std::int64_t ticks, LinearPlant p, Reference r, Disturbance d, double sigma_m,
               std::uint64_t seed)
      : learner(l),
        plant(p),
        reference(std::move(r)),
        disturbance(std::move(d)),
        sigma(sigma_m),
        rng(seed),
        ref(static_cast<std::size_t>(ticks + kHorizon + kBlock)),
        corr(ref.size()),
        y(ref.size()),
        ym(ref.size()),
        adopted(ref.size()) {}

  void plan_through(std::int64_t k) {
    while (planned < k) {
      const auto i = static_cast<std::size_t>(++planned);
      ref[i] = reference(planned);
      corr[i] = learner.correction(planned, ref[i]);
      adopted[i] = learner.figures().tables_adopted;
    }
  }

  void run(std::int64_t ticks) {
    for (std::int64_t n = 0; n < ticks; ++n) {
      const std::int64_t j = now++;
      plan_through(std::max(j, delivered + horizon));
      const std::int64_t jd = j - plant.delay;
      const double u = jd >= 0 ? ref[static_cast<std::size_t>(jd)] + corr[static_cast<std::size_t>(jd)] : 0.0;
      y[static_cast<std::size_t>(j)] = plant.gain * u + disturbance(j);
      ym[static_cast<std::size_t>(j)] = y[static_cast<std::size_t>(j)] + sigma * noise(rng);
      if ((j + 1) % block == 0) {
        for (std::int64_t k = delivered + 1; k <= j; ++k) {
          learner.observe(k,
                          drop && drop(k) ? std::numeric_limits<double>::quiet_NaN() : ym[static_cast<std::size_t>(k)]);
        }
        delivered = j;
        plan_through(delivered + horizon);
      }
    }
  }

  // The period at which the first table was taken into use: L, how many periods a table lags the
  // one it was learned from (the loop keeps it constant).
  std::int64_t first_adoption_period(std::int64_t n) const {
    std::size_t k = 0;
    while (k < adopted.size() && adopted[k] == 0) ++k;
    return static_cast<std::int64_t>(k) / n;
  }

  // RMS of the true error r - y over [from, to).
  double error_rms(std::int64_t from, std::int64_t to) const {
    double s = 0.0;
    for (std::int64_t k = from; k < to; ++k) {
      const double e = ref[static_cast<std::size_t>(k)] - y[static_cast<std::size_t>(k)];
      s += e * e;
    }
    return std::sqrt(s / static_cast<double>(to - from));
  }
  double max_error(std::int64_t from, std::int64_t to) const {
    double m = 0.0;
    for (std::int64_t k = from; k < to; ++k) {
      m = std::max(m, std::abs(ref[static_cast<std::size_t>(k)] - y[static_cast<std::size_t>(k)]));
    }
    return m;
  }
  double largest_correction() const {
    double m = 0.0;
    for (std::int64_t k = 0; k <= planned; ++k) m = std::max(m, std::abs(corr[static_cast<std::size_t>(k)]));
    return m;
  }

  PeriodicLearner& learner;
  LinearPlant plant;
  Reference reference;
  Disturbance disturbance;
  std::function<bool(std::int64_t)> drop;  // ticks whose sample is lost (NaN)
  double sigma;
  std::mt19937_64 rng;
  std::normal_distribution<double> noise{0.0, 1.0};
  std::vector<double> ref, corr, y, ym;
  std::vector<std::uint64_t> adopted;  // figures().tables_adopted after planning tick k
  // How far the plan runs ahead of the last sample and how many samples arrive at once (0 and 1:
  // the table from a period is in use from the next one on, L = 1).
  std::int64_t horizon = kHorizon, block = kBlock;
  std::int64_t now = 0, planned = -1, delivered = -1;
};

}  // namespace hystloop::testing
