#pragma once
// Online refit of the MEM parameters from streamed samples (the re-identifier's core).
//
// Threading contract (no locks anywhere):
//   * ONE owner thread calls feed(), snapshot(), adopt(), params(). feed() is the per-sample
//     path: it writes one (u, y) pair into a preallocated ring and updates counters; noexcept,
//     no allocation, no lock (~5 ns).
//   * snapshot() copies the most recent window out of the ring into a MemWindow made by
//     make_window() (no allocation then); the owner does this between samples, so the ring is
//     never read while it is written.
//   * evaluate() is a pure function of its arguments (a window copy and the parameter set in use
//     with its version): run it on ANY thread, it shares nothing with the estimator. It is
//     time-bounded by options.fit.max_solver_time_s plus the variable-projection search.
//   * adopt() (owner thread) publishes an accepted outcome only if the parameters it was judged
//     against are still the ones in use (their version), so a slow refit cannot overwrite a newer
//     decision.
// A candidate is accepted only if (1) the fit succeeded and the parameters are in range,
// (2) its residual is below the bounds, and (3) it predicts the most recent complete branch(es),
// held out from the fit, better than the set in use by min_relative_improvement.
// Non-finite samples and sensor dropouts (y exactly stuck while u moves) are counted; a window
// holding any of them is refused with poisoned_window, so no garbage reaches a fit.

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "ident/fit_status.hpp"
#include "ident/mem_fit.hpp"
#include "models/mem.hpp"

namespace hystloop {

struct OnlineMemOptions {
  std::size_t capacity_samples = 200000;   // ring size: 20 s at 10 kHz, preallocated
  std::size_t window_samples = 20000;      // refit window: 2 s at 10 kHz
  std::size_t holdout_branches = 1;        // most recent complete branches kept out of the fit
  double min_relative_improvement = 0.02;  // held-out RMS must drop by this fraction
  double max_residual_rms_m = 20e-9;       // validation bound on the fit residual (absolute) ...
  double max_relative_residual = 0.05;     // ... and relative to the window's half output range
  std::size_t stuck_samples = 50;          // y bit-identical this long while u moves: a dropout
  MemFitOptions fit{};                     // fit.max_solver_time_s bounds the solver

  void validate() const;  // throws ParameterError naming the field
};

enum class PoisonKind : std::uint8_t { none, non_finite, dropout };

// A copy of the recent samples, oldest first.
struct MemWindow {
  std::vector<double> u, y;     // capacity = window_samples, size = samples copied
  std::uint64_t first_seq = 0;  // sequence number of u[0]
  PoisonKind poison = PoisonKind::none;
  std::uint64_t poison_seq = 0;
};

enum class FeedResult : std::uint8_t { stored, non_finite, dropout };

struct MemRefitOutcome {
  FitStatus status = FitStatus::solver_failure;  // ok = accepted
  std::string reason;
  bool accepted = false;
  MemParams candidate{};
  MemFitResult fit{};
  double holdout_rms_candidate_m = 0.0;
  double holdout_rms_in_use_m = 0.0;
  std::uint64_t judged_against_version = 0;
};

class OnlineMemEstimator {
 public:
  OnlineMemEstimator(const OnlineMemOptions& options, const MemParams& initial);  // validates both

  FeedResult feed(double u_V, double y_m) noexcept;

  MemWindow make_window() const;        // preallocated for snapshot()
  void snapshot(MemWindow& out) const;  // allocation-free into a window from make_window()

  static MemRefitOutcome evaluate(const MemWindow& window, const MemParams& in_use, std::uint64_t in_use_version,
                                  const OnlineMemOptions& options);
  // Publishes an accepted outcome judged against the current version. Returns true if it did.
  bool adopt(const MemRefitOutcome& outcome);
  // snapshot + evaluate + adopt on the calling (owner) thread.
  MemRefitOutcome refit();

  const MemParams& params() const noexcept { return params_; }
  std::uint64_t version() const noexcept { return version_; }
  const OnlineMemOptions& options() const noexcept { return options_; }
  std::uint64_t samples_fed() const noexcept { return seq_; }
  // The window starts again: what was fed before belongs to another reference, and a window
  // holding two is fitted by a set that explains neither. A window is full again after
  // window_samples more (samples_since_restart).
  void restart_window() noexcept { window_start_ = seq_; }
  std::uint64_t samples_since_restart() const noexcept { return seq_ - window_start_; }
  // A window snapshot taken when `fed` samples had been fed holds another reference's samples.
  bool restarted_since(std::uint64_t fed) const noexcept { return window_start_ > 0 && window_start_ >= fed; }
  std::uint64_t non_finite_samples() const noexcept { return non_finite_; }
  std::uint64_t dropouts() const noexcept { return dropouts_; }
  std::uint64_t refits_accepted() const noexcept { return accepted_; }
  std::uint64_t refits_rejected() const noexcept { return rejected_; }

 private:
  OnlineMemOptions options_;
  MemParams params_;
  std::uint64_t version_ = 1;
  std::vector<double> u_, y_;       // the ring
  std::uint64_t seq_ = 0;           // samples fed; next write at seq_ % capacity
  std::uint64_t window_start_ = 0;  // seq_ at the last restart_window()
  double last_u_ = 0.0, last_y_ = 0.0;
  std::size_t stuck_run_ = 0;
  PoisonKind poison_ = PoisonKind::none;
  std::uint64_t poison_seq_ = 0;  // sequence number of the latest poisoned sample
  std::uint64_t non_finite_ = 0, dropouts_ = 0, accepted_ = 0, rejected_ = 0;
  MemWindow scratch_;  // refit()'s window
};

std::string_view to_string(PoisonKind kind) noexcept;

}  // namespace hystloop
