#include "models/axis_coupling.hpp"

#include <cmath>
#include <cstdio>
#include <limits>

#include <Eigen/LU>
#include <Eigen/SVD>

#include "core/errors.hpp"

namespace hystloop {
namespace {

// The n x n block in fixed storage: Eigen's decompositions of it allocate nothing.
using Block = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::ColMajor, kMaxAxes, kMaxAxes>;

std::string entry_field(int j, int i) { return "coupling[" + std::to_string(j) + "][" + std::to_string(i) + "]"; }

// Sum over the n x n block of m(i, j) v(j), skipping exact zeros so that a non-finite v(j) reaches
// only the axes actually coupled to j (0 * NaN would be NaN). Entries >= n pass through.
AxisVector apply(const AxisMatrix& m, int n, const AxisVector& v) noexcept {
  AxisVector out = v;
  for (int i = 0; i < n; ++i) {
    double sum = 0.0;
    for (int j = 0; j < n; ++j) {
      if (m(i, j) != 0.0) sum += m(i, j) * v(j);
    }
    out(i) = sum;
  }
  return out;
}

}  // namespace

std::string axis_field(std::string_view field, int axis) {
  if (axis == 0) return std::string(field);
  const std::size_t dot = field.find('.');
  const std::string name(axis_name(axis));
  if (dot == std::string_view::npos) return name + "." + std::string(field);
  return std::string(field.substr(0, dot + 1)) + name + "." + std::string(field.substr(dot + 1));
}

std::string_view axis_name(int axis) noexcept {
  switch (axis) {
    case 0: return "x";
    case 1: return "y";
    case 2: return "z";
    default: return "?";
  }
}

AxisCoupling::AxisCoupling(int n, const AxisMatrix& c) {
  // n first: the block below is read with it.
  if (n < 1 || n > kMaxAxes) {
    throw ParameterError("n", "must be in [1, " + std::to_string(kMaxAxes) + "] axes (got " + std::to_string(n) + ")");
  }
  n_ = n;
  c_ = AxisMatrix::Identity();
  c_.topLeftCorner(n, n) = c.topLeftCorner(n, n);
  validate();
  const Block block = c_.topLeftCorner(n_, n_);
  inv_ = AxisMatrix::Identity();
  inv_.topLeftCorner(n_, n_) = block.inverse();
}

AxisCoupling AxisCoupling::identity(int n) { return {n, AxisMatrix::Identity()}; }

void AxisCoupling::validate() const {
  if (n_ < 1 || n_ > kMaxAxes) {
    throw ParameterError("n", "must be in [1, " + std::to_string(kMaxAxes) + "] axes (got " + std::to_string(n_) + ")");
  }
  for (int j = 0; j < n_; ++j) {
    for (int i = 0; i < n_; ++i) require_finite(entry_field(j, i), c_(j, i));
  }
  for (int i = 0; i < n_; ++i) {
    if (c_(i, i) != 1.0) {
      throw ParameterError(entry_field(i, i), "must be exactly 1 (got " + number_text(c_(i, i)) + "): axis " +
                                                  std::string(axis_name(i)) +
                                                  "'s own gain belongs to its own model, C holds only the coupling");
    }
  }
  for (int j = 0; j < n_; ++j) {
    for (int i = 0; i < n_; ++i) {
      if (i != j && std::abs(c_(j, i)) > kMaxCoupling) {
        throw ParameterError(entry_field(j, i), "|" + number_text(c_(j, i)) + "| exceeds " + number_text(kMaxCoupling) +
                                                    ": moving " + std::string(axis_name(i)) + " would move " +
                                                    std::string(axis_name(j)) +
                                                    " by more than half as much (a mislabelled axis or sensor?)");
      }
    }
  }
  const double cond = condition_number();
  if (!(cond <= kMaxCouplingCondition)) {
    throw ParameterError("coupling", "condition number " + number_text(cond) + " exceeds " +
                                         number_text(kMaxCouplingCondition) +
                                         ": the axes are nearly dependent, so decoupling would multiply reference "
                                         "and model errors up to that many times (a few per cent coupling gives ~1.1)");
  }
}

double AxisCoupling::condition_number() const {
  const Block block = c_.topLeftCorner(n_, n_);
  const Eigen::JacobiSVD<Block> svd(block);
  const auto& sigma = svd.singularValues();  // decreasing
  const double smallest = sigma(n_ - 1);
  if (!(smallest > 0.0)) return std::numeric_limits<double>::infinity();
  return sigma(0) / smallest;
}

AxisVector AxisCoupling::couple(const AxisVector& s) const noexcept { return apply(c_, n_, s); }

AxisVector AxisCoupling::decouple(const AxisVector& r) const noexcept { return apply(inv_, n_, r); }

std::string AxisCoupling::describe() const {
  if (n_ == 1) return std::string(axis_name(0)) + ": single axis, no coupling";
  std::string out;
  for (int i = 0; i < n_; ++i) {
    for (int j = 0; j < n_; ++j) {
      if (i == j) continue;
      double percent = 100.0 * c_(j, i);
      if (std::abs(percent) < 0.05) percent = 0.0;  // no "-0.0 %"
      char buf[32];
      std::snprintf(buf, sizeof buf, " %.1f %%", percent);
      if (!out.empty()) out += ", ";
      out.append(axis_name(i)).append("->").append(axis_name(j)).append(buf);
    }
  }
  return out;
}

std::string describe_coupling(const AxisMatrix& c, int n) {
  std::string out;
  for (const CouplingEntry& e : kCouplingEntries) {
    if (e.to >= n || e.from >= n || c(e.to, e.from) == 0.0) continue;
    char value[32];
    std::snprintf(value, sizeof value, "%+.4g", c(e.to, e.from));
    out += ", " + std::string(axis_name(e.from)) + " -> " + std::string(axis_name(e.to)) + " " + value;
  }
  return out.empty() ? " none" : out;
}

}  // namespace hystloop
