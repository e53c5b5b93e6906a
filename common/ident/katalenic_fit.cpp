#include "ident/katalenic_fit.hpp"

#include <ceres/ceres.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <sstream>
#include <vector>

#include "core/errors.hpp"
#include "ident/branches.hpp"
#include "ident/ceres_budget.hpp"
#include "ident/fit_checks.hpp"

namespace hystloop {

void KatalenicFitOptions::validate() const {
  require_in_range("output_polynomial_degree", output_polynomial_degree, 1.0,
                   static_cast<double>(ShapingFunction::kMaxCoefficients - 1));
  require_non_negative("min_input_range_V", min_input_range_V);
  if (min_samples < 8) throw ParameterError("min_samples", "must be >= 8");
  require_positive("max_solver_time_s", max_solver_time_s);
  if (max_solver_iterations < 1) throw ParameterError("max_solver_iterations", "must be >= 1");
}

namespace {

struct Problem {
  std::span<const double> u, y;
  std::size_t score_begin = 0;
  int degree = 1;
  double z_scale = 1.0;  // [V]: polynomial columns in z / z_scale for conditioning
  double y_scale = 1.0;

  std::vector<double> simulate(double k1, double k2) const {
    KatalenicParams p;
    p.k1 = k1;
    p.k2 = k2;
    p.k2_domain_min = -1e300;  // k2 constant: no schedule
    p.k2_domain_max = 1e300;
    p.output_shaping = ShapingFunction::make_linear(1.0);
    return predict_katalenic(p, u);
  }
  // Least-squares shaping coefficients (in scaled columns) and the residual vector.
  Eigen::VectorXd project(const std::vector<double>& z, double* residuals) const {
    const auto n = static_cast<Eigen::Index>(u.size() - score_begin);
    Eigen::MatrixXd phi(n, degree + 1);
    Eigen::VectorXd target(n);
    for (Eigen::Index i = 0; i < n; ++i) {
      const double zz = z[score_begin + static_cast<std::size_t>(i)] / z_scale;
      double pw = 1.0;
      for (int d = 0; d <= degree; ++d) phi(i, d) = pw, pw *= zz;
      target[i] = y[score_begin + static_cast<std::size_t>(i)] / y_scale;
    }
    Eigen::VectorXd c = phi.colPivHouseholderQr().solve(target);
    if (residuals != nullptr) {
      const Eigen::VectorXd r = target - phi * c;
      std::copy(r.data(), r.data() + n, residuals);
    }
    return c;
  }
};

struct ProjectedResidual {
  const Problem* problem;
  bool operator()(double const* const* x, double* r) const {
    const double k1 = std::exp(x[0][0]), k2 = std::exp(x[0][1]);
    if (!std::isfinite(k1) || !std::isfinite(k2)) return false;
    problem->project(problem->simulate(k1, k2), r);
    return true;
  }
};

double cost(const Problem& p, double k1, double k2) {
  std::vector<double> r(p.u.size() - p.score_begin);
  p.project(p.simulate(k1, k2), r.data());
  double s = 0.0;
  for (double v : r) s += v * v;
  return s;
}

}  // namespace

std::vector<double> predict_katalenic(const KatalenicParams& params, std::span<const double> u) {
  KatalenicModel m(params);
  std::vector<double> out(u.size());
  if (u.empty()) return out;
  m.reset(u[0]);
  for (std::size_t k = 0; k < u.size(); ++k) out[k] = m.forward(u[k]);
  return out;
}

KatalenicFitResult fit_katalenic(std::span<const double> u, std::span<const double> y, const KatalenicFitOptions& o) {
  o.validate();
  const FitTimer timer(o.clock);
  KatalenicFitResult res;
  double ulo = 0.0, uhi = 0.0;
  std::size_t begin = 0;
  if (FitCheck c = check_fit_input(u, y, o.min_input_range_V, &ulo, &uhi); !c.ok()) return timer.finish(res, c);
  if (FitCheck c = check_after_second_reversal(u, o.min_samples, &begin); !c.ok()) return timer.finish(res, c);
  const double half = 0.5 * (uhi - ulo);
  Problem p{u, y, begin, o.output_polynomial_degree, half, 1.0};
  const auto [ylo, yhi] = std::minmax_element(y.begin(), y.end());
  p.y_scale = *yhi > *ylo ? 0.5 * (*yhi - *ylo) : 1.0;
  res.samples_used = u.size() - p.score_begin;
  // Grid: k1 as a fraction of the half span, k2 k1 (the transition's sharpness) from 0.3 to 10.
  double best_k1 = 0.1 * half, best_k2 = 1.0 / (0.1 * half), best = 1e300;
  for (double f1 : {0.03, 0.08, 0.2, 0.4}) {
    for (double s : {0.3, 1.0, 3.0, 10.0}) {
      const double k1 = f1 * half, k2 = s / k1;
      const double c = cost(p, k1, k2);
      if (c < best) best = c, best_k1 = k1, best_k2 = k2;
    }
  }
  double x[2] = {std::log(best_k1), std::log(best_k2)};
  ceres::Problem problem;
  auto* fn = new ceres::DynamicNumericDiffCostFunction<ProjectedResidual, ceres::CENTRAL>(new ProjectedResidual{&p});
  fn->AddParameterBlock(2);
  fn->SetNumResiduals(static_cast<int>(res.samples_used));
  problem.AddResidualBlock(fn, nullptr, x);
  ceres::Solver::Options so;
  so.linear_solver_type = ceres::DENSE_QR;
  so.max_num_iterations = o.max_solver_iterations;
  so.logging_type = ceres::SILENT;
  detail::CeresTimeBudget budget(timer.clock(), o.max_solver_time_s);
  budget.attach(so);
  ceres::Solver::Summary summary;
  ceres::Solve(so, &problem, &summary);
  if (!summary.IsSolutionUsable()) return timer.finish(res, FitStatus::solver_failure, "Ceres: " + summary.message);
  res.params.k1 = std::exp(x[0]);
  res.params.k2 = std::exp(x[1]);
  res.params.k2_slope = 0.0;
  const std::vector<double> z = p.simulate(res.params.k1, res.params.k2);
  const Eigen::VectorXd c = p.project(z, nullptr);
  // Back to metres and operator units: psi_out(z) = y_scale * sum c_d (z / z_scale)^d.
  if (o.output_polynomial_degree == 1) {
    res.params.output_shaping = ShapingFunction::make_linear(p.y_scale * c[1] / p.z_scale, p.y_scale * c[0]);
  } else {
    const auto [zlo, zhi] = std::minmax_element(z.begin(), z.end());
    ShapingFunction s;
    s.kind = ShapingKind::polynomial;
    s.domain_min = *zlo;
    s.domain_max = *zhi;
    for (int d = 0; d <= o.output_polynomial_degree; ++d) {
      s.coefficients[static_cast<std::size_t>(d)] = p.y_scale * c[d] / std::pow(p.z_scale, d);
    }
    res.params.output_shaping = s;
  }
  res.residual_rms_m = p.y_scale * std::sqrt(2.0 * summary.final_cost / static_cast<double>(res.samples_used));
  // A fit that is not a fit (k1 run off to 1e301, a NaN residual) is a refusal.
  FitCheck check = check_katalenic_params(res.params, 2.0 * half);
  if (check.ok()) check = check_fit_residual(res.residual_rms_m, *yhi - *ylo);
  if (!check.ok()) return timer.finish(res, check);
  return timer.finish(res, FitStatus::ok);
}

}  // namespace hystloop
