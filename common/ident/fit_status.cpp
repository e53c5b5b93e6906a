#include "ident/fit_status.hpp"

namespace hystloop {

std::string_view to_string(FitStatus status) noexcept {
  switch (status) {
    case FitStatus::ok: return "ok";
    case FitStatus::size_mismatch: return "size_mismatch";
    case FitStatus::non_finite_data: return "non_finite_data";
    case FitStatus::constant_input: return "constant_input";
    case FitStatus::too_few_branches: return "too_few_branches";
    case FitStatus::too_few_samples: return "too_few_samples";
    case FitStatus::out_of_range: return "out_of_range";
    case FitStatus::solver_failure: return "solver_failure";
    case FitStatus::no_improvement: return "no_improvement";
    case FitStatus::poisoned_window: return "poisoned_window";
  }
  return "unknown";
}

}  // namespace hystloop
