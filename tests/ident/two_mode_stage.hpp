#pragma once
// The tests' own linear stage: two lightly damped modes in parallel (unit DC gain), an input delay,
// driven through a zero-order hold at fs and sampled at the ticks. Simulated exactly per tick
// (matrix exponential with the delay split across the hold); its true sampled response is given
// independently by the aliasing (Poisson) sum over the continuous response, which the simulator
// is checked against.

#include <Eigen/Dense>
#include <unsupported/Eigen/MatrixFunctions>
#include <cmath>
#include <complex>
#include <cstddef>
#include <cstdint>
#include <numbers>
#include <random>
#include <vector>

namespace hystloop::test {

struct TwoModeStage {
  double f1_Hz = 780.0, zeta1 = 0.03, gain1 = 0.8;
  double f2_Hz = 2400.0, zeta2 = 0.02, gain2 = 0.2;
  double delay_s = 150e-6;  // 1.5 ticks at 10 kHz
  double sample_rate_Hz = 1e4;

  double w1() const { return 2.0 * std::numbers::pi * f1_Hz; }
  double w2() const { return 2.0 * std::numbers::pi * f2_Hz; }

  // Continuous G(s) without the delay.
  std::complex<double> g(std::complex<double> s) const {
    return gain1 * w1() * w1() / (s * s + 2.0 * zeta1 * w1() * s + w1() * w1()) +
           gain2 * w2() * w2() / (s * s + 2.0 * zeta2 * w2() * s + w2() * w2());
  }
  std::complex<double> continuous_response(double f_Hz) const {
    const double w = 2.0 * std::numbers::pi * f_Hz;
    return g({0.0, w}) * std::polar(1.0, -w * delay_s);
  }
  // Sampled response through the hold: sum over the images w + k ws of G e^{-s tau} (1 - e^{-sT}) / (sT).
  std::complex<double> sampled_response(double f_Hz, int images = 4000) const {
    const double T = 1.0 / sample_rate_Hz, ws = 2.0 * std::numbers::pi * sample_rate_Hz;
    std::complex<double> sum = 0.0;
    for (int k = -images; k <= images; ++k) {
      const double w = 2.0 * std::numbers::pi * f_Hz + k * ws;
      const std::complex<double> s(0.0, w);
      sum += g(s) * std::exp(-s * delay_s) * (1.0 - std::exp(-s * T)) / (s * T);
    }
    return sum;
  }
  // Poles and zeros [rad/s] of G(s).
  std::vector<std::complex<double>> poles() const {
    std::vector<std::complex<double>> p;
    for (auto [w, z] : {std::pair{w1(), zeta1}, std::pair{w2(), zeta2}}) {
      p.emplace_back(-z * w, w * std::sqrt(1.0 - z * z));
      p.emplace_back(-z * w, -w * std::sqrt(1.0 - z * z));
    }
    return p;
  }
  std::vector<std::complex<double>> zeros() const {
    // g1 w1^2 (s^2 + 2 z2 w2 s + w2^2) + g2 w2^2 (s^2 + 2 z1 w1 s + w1^2)
    const double a = gain1 * w1() * w1() + gain2 * w2() * w2();
    const double b = gain1 * w1() * w1() * 2.0 * zeta2 * w2() + gain2 * w2() * w2() * 2.0 * zeta1 * w1();
    const double c = (gain1 + gain2) * w1() * w1() * w2() * w2();
    const std::complex<double> d = std::sqrt(std::complex<double>(b * b - 4.0 * a * c));
    return {(-b + d) / (2.0 * a), (-b - d) / (2.0 * a)};
  }

  // y[k] for the held input u[k] (from rest), plus white noise of noise_sd, seeded.
  std::vector<double> simulate(const std::vector<double>& u, double noise_sd, std::uint64_t seed) const {
    Eigen::Matrix4d A = Eigen::Matrix4d::Zero();
    Eigen::Vector4d B = Eigen::Vector4d::Zero();
    Eigen::RowVector4d Cr = Eigen::RowVector4d::Zero();
    // States: position and velocity / w of each mode (balanced, for an accurate exponential).
    A(0, 1) = w1(), A(1, 0) = -w1(), A(1, 1) = -2.0 * zeta1 * w1(), B(1) = gain1 * w1();
    A(2, 3) = w2(), A(3, 2) = -w2(), A(3, 3) = -2.0 * zeta2 * w2(), B(3) = gain2 * w2();
    Cr(0) = 1.0, Cr(2) = 1.0;
    const double T = 1.0 / sample_rate_Hz;
    const auto l = static_cast<std::size_t>(std::floor(delay_s / T));
    const double theta = delay_s - static_cast<double>(l) * T;
    auto integral = [&](double t) {  // {e^{At}, int_0^t e^{As} ds B}
      Eigen::Matrix<double, 5, 5> m = Eigen::Matrix<double, 5, 5>::Zero();
      m.topLeftCorner<4, 4>() = A * t;
      m.topRightCorner<4, 1>() = B * t;
      const Eigen::Matrix<double, 5, 5> e = m.exp();
      return std::pair<Eigen::Matrix4d, Eigen::Vector4d>{e.topLeftCorner<4, 4>(), e.topRightCorner<4, 1>()};
    };
    const Eigen::Matrix4d Phi = integral(T).first;
    const auto [E0, G0] = integral(T - theta);
    const Eigen::Vector4d G1 = E0 * integral(theta).second;
    std::mt19937_64 rng(seed);
    std::normal_distribution<double> noise(0.0, noise_sd);
    Eigen::Vector4d x = Eigen::Vector4d::Zero();
    std::vector<double> y(u.size());
    auto at = [&](std::size_t k, std::size_t back) { return k >= back ? u[k - back] : 0.0; };
    for (std::size_t k = 0; k < u.size(); ++k) {
      y[k] = Cr * x + (noise_sd > 0.0 ? noise(rng) : 0.0);
      x = Phi * x + G0 * at(k, l) + G1 * at(k, l + 1);
    }
    return y;
  }
};

}  // namespace hystloop::test
