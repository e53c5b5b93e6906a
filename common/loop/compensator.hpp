#pragma once
// The compensator's control law without I/O or a clock: for each sensor sample of
// tick k it produces the command for tick k + lead_ticks,
//
//   u = u_ff + u_fb,   u_ff = H^-1( y_ref(t_{k+lead}) ),   u_fb = PID( y_ref(t_k) - y_k ),
//
// with H^-1 the inverse of the selected hysteresis model. Loop time is t_k = k * dt,
// so the output is a deterministic function of the messages it is given, in order:
// a recorded log replays to the same commands (tools/replay-check relies on it).
// New MEM parameters are validated when offered and swapped in at the next reversal
// of the reference, where the inverse's branch restarts, so the voltage does not jump.

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "loop/feedback.hpp"
#include "loop/trajectory.hpp"
#include "models/katalenic.hpp"
#include "models/linear.hpp"
#include "models/mem.hpp"
#include "models/prandtl_ishlinskii.hpp"

namespace hystloop {

// Which feedforward; numbering shared with actuator_command_t.mode / control_t.mode.
enum class FeedforwardMode : std::int8_t {
  kOff = 0,        // no feedforward: u = u_fb (0 V without feedback)
  kLinear = 1,     // static gain: the MEM paper's "linear feedforward"
  kMem = 2,        // hybrid MEM element inverse (Strijbosch et al., Theorem 10)
  kPi = 3,         // Prandtl-Ishlinskii inverse
  kKatalenic = 4,  // Lambert-W operator inverse
  kExperiment = 5  // identification excitation: raw voltage, no reference (not selectable as a mode)
};

// Parses "off|linear|mem|pi|katalenic"; throws ParameterError naming `field`.
FeedforwardMode parse_feedforward_mode(const std::string& name, const std::string& field = "compensator.mode");
const char* to_string(FeedforwardMode mode) noexcept;

struct CompensatorConfig {
  FeedforwardMode mode = FeedforwardMode::kMem;
  MemParams mem{};
  PiParams pi = pi_params_from_mem(MemParams::paper_like(), 15, 250.0);  // the MEM paper's 15 plays
  KatalenicParams katalenic{};
  LinearParams linear{};
  FeedbackGains feedback{};   // all zero = feedforward only
  std::int64_t lead_ticks = 2;  // command for tick k + lead answers sample k
  double dt_s = 1e-4;           // the bridge's tick

  void validate() const;  // throws ParameterError naming the field
};

// An identification excitation u(t) = offset + amplitude * sin(2 pi f (t - start)),
// run for a whole number of periods. It starts at the first command produced after it was
// given (start = that command's loop time); experiments given while one runs wait in a queue
// and run back to back (the next starts at the loop time the previous ended, so a series of
// whole-period sines is one continuous input); when none is left the compensator returns to
// its mode. `settle` only labels the segment: the same sine, run to bring the hysteresis to
// its stationary loop, whose samples identification skips (Banning's series).
struct ExperimentSpec {
  double amplitude_V = 250.0;
  double offset_V = 0.0;
  double frequency_hz = 10.0;  // the MEM paper's identification input: 250 sin(20 pi t)
  double duration_s = 2.0;     // rounded up to whole periods
  bool settle = false;
  void validate() const;
};

// The experiment a START_EXPERIMENT request names: kind "sine", or "settle" (the same sine,
// labelled). Validated; throws ParameterError ("experiment" for another kind).
ExperimentSpec make_experiment_spec(std::string_view kind, double amplitude_V, double offset_V, double frequency_hz,
                                    double duration_s);
// The voltage an experiment commands t_s after its start [V].
double experiment_voltage(const ExperimentSpec& spec, double t_s) noexcept;
// Loop time [s] at which an experiment started at start_s ends: after its whole periods.
double experiment_end_s(double start_s, const ExperimentSpec& spec) noexcept;
// The first tick k whose loop time k * dt_s is at or after t_s: the first command past an
// experiment that ends at t_s. With experiment_end_s this reproduces the compensator's
// schedule from a log (tools/identify splits Banning's series with it).
std::int64_t first_tick_at_or_after(double t_s, double dt_s) noexcept;

// The command ticks [begin, end) of experiments run back to back, the first starting at
// first_tick: what the compensator commands when all of them were given in time.
struct ExperimentTicks {
  std::int64_t begin = 0;
  std::int64_t end = 0;
};
std::vector<ExperimentTicks> experiment_schedule(std::int64_t first_tick, std::span<const ExperimentSpec> specs,
                                                 double dt_s);

struct CompensatorInput {
  std::int64_t seq = 0;  // tick of the sample
  double u_V = 0.0;      // voltage applied at that tick
  double y_m = 0.0;      // measured position
};

struct CompensatorOutput {
  std::int64_t seq = 0;          // tick the command is for
  std::int64_t sample_seq = 0;   // tick of the sample it answers
  double u_V = 0.0;
  double u_ff_V = 0.0;
  double u_fb_V = 0.0;
  double y_ref_m = 0.0;          // reference for tick `seq` (NaN during an experiment)
  double error_m = 0.0;          // y_ref - y at the sample's tick (NaN when no reference)
  std::int32_t params_version = 0;
  FeedforwardMode mode = FeedforwardMode::kOff;
  bool reversal = false;         // the reference reversed at this command
};

struct CompensatorCounters {
  std::uint64_t samples = 0;
  std::uint64_t out_of_order = 0;   // samples whose seq did not increase (ignored)
  std::uint64_t gaps = 0;           // missing sample ticks
  std::uint64_t params_accepted = 0;
  std::uint64_t params_rejected = 0;
  std::uint64_t params_swapped = 0;
  std::uint64_t nonfinite_outputs = 0;  // model produced NaN/Inf: the last voltage was held
};

class Compensator {
 public:
  explicit Compensator(const CompensatorConfig& config);  // validates

  // One sample in, one command out. Allocation-, lock- and throw-free.
  // Nothing when the sample is out of order (its seq did not increase).
  std::optional<CompensatorOutput> update(const CompensatorInput& sample) noexcept;

  // A new reference; spec.start_s is loop time (k * dt). Validated here (throws).
  void set_trajectory(const TrajectorySpec& spec);
  // Starts the approach to the reference `lead_ticks` after the last sample, from where
  // the reference is now; the shape itself starts blend_s later.
  void start_trajectory_now(TrajectorySpec spec);

  // New MEM parameters; validated (throws ParameterError) and swapped at the next reversal.
  void offer_mem_params(const MemParams& params, std::int32_t version);
  void set_mode(FeedforwardMode mode);   // re-initialises that inverse at the current reference
  void set_gains(const FeedbackGains& gains);
  // Starts the experiment with the next command, or queues it behind the running one.
  // Validated here (throws ParameterError; also when kExperimentQueue are already waiting).
  void start_experiment(const ExperimentSpec& spec);
  // Ends the running experiment after the commands already produced and drops the queue.
  void stop_experiment() noexcept;
  static constexpr std::size_t kExperimentQueue = 128;

  const CompensatorCounters& counters() const noexcept { return counters_; }
  FeedforwardMode mode() const noexcept { return mode_; }
  const MemParams& mem_params() const noexcept { return mem_.params(); }
  std::int32_t params_version() const noexcept { return params_version_; }
  bool experiment_running() const noexcept { return experiment_.has_value(); }
  std::size_t experiments_queued() const noexcept { return queued_; }
  double loop_time(std::int64_t seq) const noexcept { return static_cast<double>(seq) * config_.dt_s; }
  std::int64_t last_seq() const noexcept { return last_seq_; }
  const CompensatorConfig& config() const noexcept { return config_; }

 private:
  double feedforward(double y_ref) noexcept;
  void reset_inverse(double y0) noexcept;

  CompensatorConfig config_;
  FeedforwardMode mode_;
  TrajectorySpec trajectory_{};
  MemInverse mem_;
  PiInverse pi_;
  KatalenicInverse katalenic_;
  LinearInverse linear_;
  FeedbackController feedback_;
  std::optional<MemParams> pending_mem_;
  std::int32_t pending_version_ = 0;
  std::int32_t params_version_ = 0;

  struct RunningExperiment {
    ExperimentSpec spec;
    bool started = false;  // start_s/end_s are set by the first command it produces
    double start_s = 0.0;
    double end_s = 0.0;
  };
  std::optional<RunningExperiment> experiment_;
  std::array<ExperimentSpec, kExperimentQueue> queue_{};  // ring: waiting experiments
  std::size_t queue_head_ = 0;
  std::size_t queued_ = 0;

  // References already commanded, by tick, for the error at the sample's tick.
  static constexpr std::size_t kRefRing = 256;
  std::array<double, kRefRing> ref_by_tick_{};
  std::array<std::int64_t, kRefRing> ref_tick_{};  // which tick each slot holds (-1: none)
  std::int64_t last_seq_ = -1;
  double last_ref_ = 0.0;       // last reference commanded
  double last_u_ = 0.0;         // last voltage commanded
  double last_dir_ = 0.0;       // sign of the last non-zero reference change
  bool inverse_fresh_ = true;   // next reference initialises the inverse
  struct Anchor {
    double u_V;
    double y_m;
  };
  std::optional<Anchor> anchor_;  // where the stage is, when it is not virgin
  CompensatorCounters counters_;
};

}  // namespace hystloop
