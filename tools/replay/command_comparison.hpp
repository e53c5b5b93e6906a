#pragma once
// Compares the commands a replayed compensator published with those in the recorded log,
// tick by tick (u_ff_V, y_ref_m, mode, params_version: what a command carries; the servo's
// part is the bridge's). Only ticks the original commanded are compared, whatever blocks
// they came in. Exact by default: the compensator is a deterministic function of its
// inputs, so every double must be bitwise equal; a tolerance can be stated for the
// feedforward voltage and the reference position instead.
//
// A tick the replay did not command is "lost in transport" when the sample the original
// planned it at was played (the replay's own UDP lost a block, or the recorder did) — not a
// divergence of the control law. Divergences at or after the first lost sample may be caused by the loss
// (the replayed compensator saw a gap the original did not), so they are reported as such.

#include <cstdint>
#include <optional>
#include <set>
#include <string>

#include "recorded_commands.hpp"

namespace hystloop::replay {

struct CompareTolerance {
  double voltage_V = 0.0;   // u_ff_V; 0 = bitwise equal
  double position_m = 0.0;  // y_ref_m; 0 = bitwise equal
  void validate() const;    // throws ParameterError naming the field
};

inline constexpr int kComparedFields = 4;

struct Divergence {
  std::int64_t seq = 0;         // tick of the command
  std::int64_t sample_seq = 0;  // last sensor tick the original had when it planned it
  std::string field;            // "u_ff_V", "y_ref_m", "mode", "params_version"
  double expected = 0.0;
  double got = 0.0;
  int fields_differing = 0;  // how many of the kComparedFields fields differ at this tick
};

enum class CompareVerdict {
  kEqual,          // every tick the original commanded was reproduced
  kDiverged,       // a command differs, or is missing without a transport explanation, or nothing was compared
  kTransportLoss,  // the replay lost samples; no divergence before the first loss
};
const char* to_string(CompareVerdict verdict) noexcept;

struct CompareReport {
  std::uint64_t expected_ticks = 0;  // ticks the original commanded
  std::uint64_t compared = 0;        // of those, ticks the replay also commanded
  std::uint64_t equal = 0;
  std::uint64_t differing = 0;
  std::uint64_t lost_in_transport = 0;    // original ticks whose sample was played but that the replay did not command
  std::uint64_t missing_in_actual = 0;    // original ticks the replay did not command, not explained by a loss
  std::uint64_t missing_in_expected = 0;  // replayed ticks the original did not command (not compared)
  std::optional<std::int64_t> first_seq;  // range of the compared ticks
  std::optional<std::int64_t> last_seq;
  std::optional<Divergence> first_divergence;
  std::optional<std::int64_t> first_lost_sample;  // sample seq
  std::optional<std::int64_t> first_missing_seq;  // command seq
  bool divergence_after_loss = false;             // first divergence at/after the first lost sample

  CompareVerdict verdict() const noexcept;
  int exit_code() const noexcept;  // 0 equal, 1 diverged or transport loss (the verdict line tells which)
};

// `played_samples`: sensor ticks the replay played to the compensator; a tick the replay did
// not command is lost in transport when the sample_seq the original planned it at was
// played. When null, when that sample_seq lies inside the range the replay answered.
CompareReport compare_commands(const CommandLog& expected, const CommandLog& actual,
                               const std::set<std::int64_t>* played_samples, const CompareTolerance& tolerance);

// Multi-line human-readable report: the first divergence (tick, field, expected, got) and the summary.
std::string format_report(const CompareReport& report, const CompareTolerance& tolerance);

}  // namespace hystloop::replay
