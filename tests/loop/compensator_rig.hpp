#pragma once
// What compensator_test and compensator_experiment_test drive the Compensator with: a recorder of
// everything it plans, and a loop around it with an ideal bridge (applies the planned feedforward
// at its tick, holds the last one when none was planned, no servo) and a MEM plant, the exact
// inverse of the compensator's default MEM parameters.

#include <gtest/gtest.h>

#include <bit>
#include <cstdint>
#include <map>
#include <vector>

#include "loop/compensator.hpp"
#include "models/mem.hpp"

namespace hystloop::testing {

inline constexpr double kDt = 1e-4;

inline CompensatorConfig compensator_config(FeedforwardMode mode, std::int64_t horizon_ticks) {
  CompensatorConfig c;
  c.mode = mode;
  c.horizon_ticks = horizon_ticks;
  // These rigs test when things take effect, with steps and short approaches that no real
  // actuator could follow: an actuator without limits here (compensator_limits_test has them).
  c.u_min_V = -1e6;
  c.u_max_V = 1e6;
  c.slew_V_per_s = 1e12;
  // ... and the re-anchoring ramp as fast as with the real actuator's slew limit.
  c.slew_fraction = CompensatorConfig{}.slew_fraction * CompensatorConfig{}.slew_V_per_s / c.slew_V_per_s;
  return c;
}

// Every tick planned, in order; fails the test if a tick is planned twice or out of order.
class PlanRecorder {
 public:
  explicit PlanRecorder(std::size_t chunk = 1000) : scratch_(chunk) {}

  // Plans until the compensator has nothing left; returns how many ticks.
  std::size_t drain(Compensator& c) {
    std::size_t total = 0;
    while (const std::size_t n = c.plan(scratch_)) {
      EXPECT_LE(n, scratch_.size());
      for (std::size_t i = 0; i < n; ++i) {
        const CommandTick& t = scratch_[i];
        EXPECT_TRUE(by_seq_.empty() || t.seq > by_seq_.rbegin()->first) << "tick " << t.seq << " planned again or late";
        by_seq_[t.seq] = t;
        ticks_.push_back(t);
      }
      total += n;
    }
    return total;
  }

  const std::vector<CommandTick>& ticks() const noexcept { return ticks_; }
  const CommandTick* find(std::int64_t seq) const {
    const auto it = by_seq_.find(seq);
    return it == by_seq_.end() ? nullptr : &it->second;
  }
  const CommandTick& at(std::int64_t seq) const {
    const CommandTick* t = find(seq);
    EXPECT_NE(t, nullptr) << "tick " << seq << " was not planned";
    static const CommandTick none{};
    return t != nullptr ? *t : none;
  }

 private:
  std::vector<CommandTick> scratch_;
  std::vector<CommandTick> ticks_;
  std::map<std::int64_t, CommandTick> by_seq_;
};

// Bit-for-bit equality of two plans (NaN references compare by their bits).
inline bool same_tick(const CommandTick& a, const CommandTick& b) {
  return a.seq == b.seq && std::bit_cast<std::uint64_t>(a.u_ff_V) == std::bit_cast<std::uint64_t>(b.u_ff_V) &&
         std::bit_cast<std::uint64_t>(a.y_ref_m) == std::bit_cast<std::uint64_t>(b.y_ref_m) &&
         a.params_version == b.params_version && a.mode == b.mode;
}

// The compensator in a loop: samples reach it one tick at a time, and it answers every
// block_ticks samples, as the services do.
struct CompensatorLoop {
  explicit CompensatorLoop(const CompensatorConfig& config, int block_ticks = 10) : comp(config), block(block_ticks) {}

  // Runs n ticks; after observing tick k, on_sample(k) (optional) may act on the compensator.
  template <class OnSample>
  void run(std::int64_t n, OnSample&& on_sample) {
    for (std::int64_t end = k + n; k < end; ++k) {
      if (const CommandTick* c = plan.find(k)) u = c->u_ff_V;  // else: late, held
      const double y = plant.forward(u);
      u_applied.push_back(u);
      y_measured.push_back(y);
      comp.observe({k, u, y});
      on_sample(k);
      if ((k + 1) % block == 0) plan.drain(comp);
    }
  }
  void run(std::int64_t n) {
    run(n, [](std::int64_t) {});
  }

  Compensator comp;
  MemModel plant{};  // the compensator's default MEM parameters: its inverse is exact
  PlanRecorder plan;
  int block;
  std::int64_t k = 0;
  double u = 0.0;
  std::vector<double> u_applied;   // by tick
  std::vector<double> y_measured;  // by tick
};

}  // namespace hystloop::testing
