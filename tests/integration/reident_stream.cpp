// Test publisher for hystloop-reidentifier (tests/integration/reident_*.sh), run inside
// tools/netns-run:
//
//   reident_stream good    --url U [--duration-s 6] [--frequency-hz 1] [--tolerance 0.03] [--expect-invalid 1]
//   reident_stream garbage --url U [--phase-s 2]
//   reident_stream shutdown --url U     sends control_t SHUTDOWN to "reidentifier" (after its first status)
//   reident_stream status  --url U      until the re-identifier's first status (it serves; exit 1 if none in 10 s)
//   every mode: [--axis x|y|z]          the axis of the re-identifier under test (its process is
//                                       "reidentifier", "reidentifier-y" or "reidentifier-z")
//
// Every mode waits for the re-identifier's first HX_STATUS; good and garbage then stream 10 kHz
// of real time as the bridge and compensator do: one sensor_block_t of 10 ticks per millisecond,
// and command_block_t for the ticks up to 30 ms (300 ticks) ahead of it, reading HX_PARAMS and
// HX_STATUS between blocks, then wait --settle-s for the last reports.
//  good:    first announces an external valid set (version 5, source "probe") equal to the
//           re-identifier's initial params; the commands say the compensator applies version 7
//           (a set the re-identifier never heard on HX_PARAMS); then streams u = 250 sin(2 pi f t),
//           y from the MEM model (common/models/mem.hpp) with gain 1.1 x the initial params + 1 nm
//           noise. Passes if a valid HX_PARAMS from "reidentifier@..." arrives with version >= 8 (above
//           the applied 7) and c1, c2 within --tolerance of the truth, and the status shows the
//           external set adopted and version 7 applied.
//           With --expect-invalid 1 (re-identifier run with --publish-invalid), the later refused
//           refits must arrive as valid = false, with their own versions, and not become the set in use.
//  garbage: three phases: y NaN on every 200th tick (sine u; the bridge's block holding it is
//           refused on the wire), constant u with noisy y, y stuck while u moves. Passes if no
//           valid set is ever published and the status counts poisoned-window and constant-input
//           refusals, non-finite samples and dropouts, and no gap for the refused blocks.
//  --axis y|z: the blocks carry every axis up to it (x, y[, z]), as a bridge of that many axes
//           sends them; the axis under test gets the streams above, the others a drive 0.6 x as
//           large through a MEM 0.8 x as steep (a fit of the wrong axis misses c1 by ~30 %) and
//           commands from version 30; good also announces a set for x (version 40, another
//           publisher), which must be left alone. Passes, beyond the above, if the published sets
//           carry the axis, their versions stay below x's 30 and 40 (not followed), and the status
//           counts the x set as params_other_axis and no block as sensor_blocks_wrong_axes.
// Prints the figures (refit time p50/max, per-block feed cost) from the last status.
// Exit status 0 = pass, 1 = fail, 2 = usage.
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <numbers>
#include <random>
#include <set>
#include <span>
#include <stdexcept>
#include <string>
#include <thread>

#include <lcm/lcm-cpp.hpp>

#include "hystloop/control_t.hpp"
#include "hystloop/mem_params_t.hpp"
#include "hystloop/command_block_t.hpp"
#include "hystloop/sensor_block_t.hpp"
#include "hystloop/service_status_t.hpp"
#include "lcm/blocks.hpp"
#include "lcm/channels.hpp"
#include "lcm/connection.hpp"
#include "lcm/message_storage.hpp"
#include "lcm/publisher.hpp"
#include "lcm/subscription.hpp"
#include "models/mem.hpp"
#include "integration/probe_common.hpp"

namespace hystloop {
namespace {

using clock = std::chrono::steady_clock;

constexpr std::int64_t kBlockTicks = 10;           // the bridge's default: 1 kHz of blocks
constexpr std::int64_t kHorizonTicks = 300;        // commands planned 30 ms ahead
constexpr std::int32_t kAppliedVersion = 7;        // what the commands of the good mode say is applied
constexpr std::int32_t kOtherAxisVersion = 30;     // what they say for the axes not under test (--axis y|z)
constexpr std::int32_t kOtherAxisSetVersion = 40;  // the set announced for x (--axis y|z)

struct Options {
  std::string mode;
  std::string url;
  std::string prefix{kDefaultRigPrefix};
  double duration_s = 6.0;
  double phase_s = 2.0;
  double frequency_hz = 1.0;
  double tolerance = 0.03;
  double settle_s = 2.5;
  bool expect_invalid = false;  // the re-identifier runs with --publish-invalid
  std::string axis = "x";       // --axis: the re-identifier's
  int axis_index = 0;
  std::string process = "reidentifier";
  double c1 = MemParams::paper_like().c1, c2 = MemParams::paper_like().c2, c3 = MemParams::paper_like().c3;
};

Options parse(int argc, char** argv) {
  Options o;
  o.mode = probe::mode_of(argc, argv, "usage: reident_stream good|garbage|shutdown|status --url U [options]");
  if (o.mode != "good" && o.mode != "garbage" && o.mode != "shutdown" && o.mode != "status") {
    throw std::invalid_argument("mode must be good, garbage, shutdown or status");
  }
  probe::parse_options(argc, argv,
                       {{"--url", &o.url},
                        {"--prefix", &o.prefix},
                        {"--duration-s", &o.duration_s},
                        {"--phase-s", &o.phase_s},
                        {"--frequency-hz", &o.frequency_hz},
                        {"--tolerance", &o.tolerance},
                        {"--settle-s", &o.settle_s},
                        {"--expect-invalid", &o.expect_invalid},
                        {"--axis", &o.axis}});
  const std::array<const char*, 3> names{"x", "y", "z"};
  const auto it = std::find(names.begin(), names.end(), o.axis);
  if (it == names.end()) throw std::invalid_argument("--axis must be x, y or z");
  o.axis_index = static_cast<int>(it - names.begin());
  if (o.axis_index > 0) o.process = "reidentifier-" + o.axis;
  return o;
}

struct Observed {
  int valid_params = 0, invalid_params = 0;
  mem_params_t best{};              // last valid set from the re-identifier
  std::set<std::int32_t> versions;  // of every set from the re-identifier
  bool duplicate_version = false;
  double first_valid_after_s = -1.0;
  int statuses = 0;
  service_status_t last_status{};
  std::map<std::string, std::int64_t> counters;  // of the last status
  // Per-block feed cost over the reports that measured one (the last ones have no blocks).
  double feed_p50_us = std::nan(""), feed_p99_us = std::nan(""), feed_max_us = 0.0;
};

class Stream {
 public:
  explicit Stream(const Options& o)
      : o_(o),
        names_(o.prefix),
        lcm_(open_lcm(o.url)),
        sensor_(*lcm_, names_.sensor, nullptr),  // unchecked: the garbage mode sends NaN on purpose
        command_pub_(*lcm_, names_.command),
        params_pub_(*lcm_, names_.params),
        params_(*lcm_, names_.params, [this](const mem_params_t& m, std::int64_t) { on_params(m); }),
        status_(*lcm_, names_.status, [this](const service_status_t& m, std::int64_t) { on_status(m); }) {
    reserve_storage(block_);
    reserve_storage(commands_);
  }

  int run() {
    if (!wait_for_status(10.0)) {
      std::fprintf(stderr, "reident_stream: no HX_STATUS from reident within 10 s\n");
      return 1;
    }
    if (o_.mode == "status") return 0;
    if (o_.mode == "shutdown") {
      probe::send_shutdown(*lcm_, names_.control, o_.process, 1);  // its status is not this mode's verdict
      return 0;
    }
    return o_.mode == "good" ? run_good() : run_garbage();
  }

 private:
  void on_params(const mem_params_t& m) {
    if (m.source.rfind(o_.process + "@", 0) != 0) return;  // our own announcements
    if (!seen_.versions.insert(m.version).second) seen_.duplicate_version = true;
    if (m.valid) {
      ++seen_.valid_params;
      seen_.best = m;
      if (seen_.first_valid_after_s < 0) seen_.first_valid_after_s = seconds_since(stream_start_);
      std::printf("reident_stream: HX_PARAMS version %d valid: c1 %.6g c2 %.6g c3 %.6g residual %.3g m, %lld samples\n",
                  m.version, m.c1, m.c2, m.c3, m.residual_m, static_cast<long long>(m.samples_used));
    } else {
      ++seen_.invalid_params;
    }
  }
  void on_status(const service_status_t& m) {
    if (m.process != o_.process) return;
    ++seen_.statuses;
    seen_.last_status = m;
    if (std::isfinite(m.loop_p50_us)) {
      seen_.feed_p50_us = m.loop_p50_us;
      seen_.feed_p99_us = std::isfinite(seen_.feed_p99_us) ? std::max(seen_.feed_p99_us, m.loop_p99_us) : m.loop_p99_us;
      seen_.feed_max_us = std::max(seen_.feed_max_us, m.loop_max_us);
    }
    seen_.counters.clear();
    for (int i = 0; i < m.n_counters; ++i)
      seen_.counters[m.counter_names[static_cast<std::size_t>(i)]] = m.counter_values[static_cast<std::size_t>(i)];
  }
  static double seconds_since(clock::time_point t) { return std::chrono::duration<double>(clock::now() - t).count(); }

  bool wait_for_status(double timeout_s) {
    const auto start = clock::now();
    while (seen_.statuses == 0 && seconds_since(start) < timeout_s)
      handle_pending(*lcm_, std::chrono::milliseconds(10));
    return seen_.statuses > 0;
  }

  static std::int64_t wall_us() {
    return std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::system_clock::now().time_since_epoch())
        .count();
  }

  // Axes per block: one for x (as before axes existed), else every axis up to the one under test.
  int block_axes() const { return o_.axis_index + 1; }

  // Commands for the ticks not yet commanded, up to (excluding) `until`, in one block; the axes
  // not under test from kOtherAxisVersion.
  void command_until(std::int64_t until, std::int32_t params_version) {
    if (commanded_ >= until) return;
    begin_block(commands_, commanded_, wall_us(), seq_ - 1, block_axes());
    constexpr double kNoReference = std::numeric_limits<double>::quiet_NaN();
    for (; commanded_ < until; ++commanded_) {
      std::array<CommandTick, 3> ticks{};
      for (int a = 0; a < block_axes(); ++a) {
        ticks[static_cast<std::size_t>(a)] =
            CommandTick{.seq = commanded_,
                        .u_ff_V = 0.0,
                        .y_ref_m = kNoReference,
                        .params_version = a == o_.axis_index ? params_version : kOtherAxisVersion,
                        .mode = command_block_t::MODE_MEM};
      }
      append_tick(commands_, std::span<const CommandTick>(ticks).first(static_cast<std::size_t>(block_axes())));
    }
    command_pub_.publish(commands_);
  }

  // Streams n ticks at 10 kHz of real time, a block of kBlockTicks per millisecond, each with the
  // commands up to kHorizonTicks ahead of it; fill(k, u, y) fills tick k.
  template <class Fill>
  void stream(std::int64_t n, std::int32_t params_version, Fill fill) {
    const auto start = clock::now();
    constexpr double kNoReference = std::numeric_limits<double>::quiet_NaN();
    for (std::int64_t k = 0; k < n; k += kBlockTicks) {
      const std::int64_t ticks = std::min(kBlockTicks, n - k);
      command_until(seq_ + ticks + kHorizonTicks, params_version);
      begin_block(block_, seq_, wall_us(), 1e-4, block_axes());
      for (std::int64_t i = 0; i < ticks; ++i) {
        double u = 0.0, y = 0.0;
        fill(k + i, u, y);
        // The other axes: their own drive through their own stage.
        const double u_other = 0.6 * u;
        const double y_other = std::isfinite(u_other) ? other_axes_.forward(u_other) : 0.0;
        std::array<SensorTick, 3> axes{};
        for (int a = 0; a < block_axes(); ++a) {
          const bool ours = a == o_.axis_index;
          axes[static_cast<std::size_t>(a)] = SensorTick{.u_V = ours ? u : u_other,
                                                         .u_ff_V = ours ? u : u_other,
                                                         .y_ref_m = kNoReference,
                                                         .y_m = ours ? y : y_other,
                                                         .flags = sensor_block_t::SIMULATED};
        }
        append_tick(block_, std::span<const SensorTick>(axes).first(static_cast<std::size_t>(block_axes())));
      }
      sensor_.publish(block_);
      seq_ += ticks;
      handle_pending(*lcm_, std::chrono::microseconds(0));
      std::this_thread::sleep_until(start + std::chrono::microseconds((k + ticks) * 100));
    }
  }

  void settle() {
    const auto start = clock::now();
    const int statuses = seen_.statuses;
    // At least two more reports after the stream, so the counters include the last refits.
    while (seconds_since(start) < o_.settle_s || seen_.statuses < statuses + 2) {
      if (seconds_since(start) > o_.settle_s + 3.0) break;
      handle_pending(*lcm_, std::chrono::milliseconds(10));
    }
  }

  // One check of a mode's verdict: a failed one is printed and counted.
  void check(bool ok, const std::string& what) {
    if (!ok) {
      std::fprintf(stderr, "reident_stream: FAIL: %s\n", what.c_str());
      ++failures_;
    }
  }

  std::int64_t counter(const std::string& name) const {
    const auto it = seen_.counters.find(name);
    return it == seen_.counters.end() ? -1 : it->second;
  }

  void print_figures() const {
    const service_status_t& st = seen_.last_status;
    std::printf(
        "reident_stream: figures: refit p50 %.1f ms, max %.1f ms (%lld refits); per-block feed p50 %.3f us, "
        "worst p99 %.3f us, max %.3f us (over the stream's reports); samples fed %lld, sensor rejected %lld, gaps "
        "%lld\n",
        static_cast<double>(counter("refit_p50_us")) * 1e-3, static_cast<double>(counter("refit_max_us")) * 1e-3,
        static_cast<long long>(counter("refits_attempted")), seen_.feed_p50_us, seen_.feed_p99_us, seen_.feed_max_us,
        static_cast<long long>(counter("samples_fed")), static_cast<long long>(counter("sensor.rejected_non_finite")),
        static_cast<long long>(counter("seq_gaps")));
    std::printf("reident_stream: status detail: %s\n", st.detail.c_str());
  }

  int run_good() {
    const MemParams initial{o_.c1, o_.c2, o_.c3};
    const MemParams truth{1.1 * o_.c1, 1.1 * o_.c2, o_.c3};
    // Someone else's set, newer than the config's: it becomes the set in use.
    mem_params_t external{};
    external.utime = 1;
    external.version = 5;
    external.c1 = initial.c1;
    external.c2 = initial.c2;
    external.c3 = initial.c3;
    external.valid = true;
    external.source = "probe";
    external.axis = static_cast<std::int8_t>(o_.axis_index);
    params_pub_.publish(external);
    if (o_.axis_index > 0) {  // x's re-identifier's business, newer than everything
      mem_params_t x_set = external;
      x_set.version = kOtherAxisSetVersion;
      x_set.publisher_id = 0x0dd;
      x_set.c1 = 0.8 * initial.c1;
      x_set.source = "probe-x";
      x_set.axis = 0;
      params_pub_.publish(x_set);
    }

    MemModel model(truth);
    std::mt19937_64 rng(42);
    std::normal_distribution<double> noise(0.0, 1e-9);
    const double w = 2.0 * std::numbers::pi * o_.frequency_hz;
    stream_start_ = clock::now();
    stream(std::llround(o_.duration_s * 1e4), kAppliedVersion, [&](std::int64_t k, double& u, double& y) {
      u = 250.0 * std::sin(w * static_cast<double>(k) * 1e-4);
      y = model.forward(u) + noise(rng);
    });
    settle();
    print_figures();
    check(seen_.valid_params >= 1, "no valid HX_PARAMS from the re-identifier");
    if (seen_.valid_params >= 1) {
      const mem_params_t& b = seen_.best;
      const double e1 = std::abs(b.c1 / truth.c1 - 1.0), e2 = std::abs(b.c2 / truth.c2 - 1.0);
      std::printf(
          "reident_stream: c1 error %.3f %%, c2 error %.3f %%, c3 %.4f (truth %.4f), version %d, first after "
          "%.2f s of stream\n",
          100 * e1, 100 * e2, b.c3, truth.c3, b.version, seen_.first_valid_after_s);
      check(e1 <= o_.tolerance, "c1 off by " + std::to_string(100 * e1) + " %");
      check(e2 <= 3 * o_.tolerance, "c2 off by " + std::to_string(100 * e2) + " %");
      check(b.version >= kAppliedVersion + 1,
            "version " + std::to_string(b.version) + " is not above the applied version 7 (nor the external set's 5)");
      check(std::isfinite(b.residual_m) && b.residual_m > 0 && b.residual_m < 20e-9, "residual_m out of range");
      check(b.axis == o_.axis_index, "the set carries axis " + std::to_string(b.axis) + ", not " + o_.axis);
      if (o_.axis_index > 0) {
        check(b.version < kOtherAxisVersion,
              "version " + std::to_string(b.version) + " follows another axis's (30 on HX_COMMAND, 40 on HX_PARAMS)");
      }
      check(b.samples_used > 0 && b.window_s > 0, "samples_used/window_s missing");
    }
    if (o_.expect_invalid) {
      // Refits after the accepted one are no better: published for diagnosis, never in use.
      check(seen_.invalid_params >= 1, "--publish-invalid published no refused candidate");
      check(counter("params_version") == seen_.best.version, "a valid = false set became the set in use");
      std::printf("reident_stream: %d diagnostic (valid = false) sets\n", seen_.invalid_params);
    } else {
      check(seen_.invalid_params == 0, "a valid = false set was published without --publish-invalid");
    }
    check(!seen_.duplicate_version, "two sets with one version");
    check(counter("params_adopted") == 1, "the external set was not adopted");
    check(counter("params_version_applied") == kAppliedVersion, "the applied version (HX_COMMAND) is not reported");
    check(counter("refits_accepted") >= 1, "status does not count the accepted refit");
    check(counter("seq_gaps") == 0, "samples were lost on the way");
    if (o_.axis_index > 0) {
      check(counter("params_other_axis") >= 1, "the set for x is not counted as another axis's");
      check(counter("params_forged") == 0, "a set was counted as forged");
      check(counter("sensor_blocks_wrong_axes") == 0, "blocks with the axis were refused");
    }
    return failures_ == 0 ? 0 : 1;
  }

  int run_garbage() {
    const MemModel truth_model(MemParams{1.1 * o_.c1, 1.1 * o_.c2, o_.c3});
    MemModel model = truth_model;
    std::mt19937_64 rng(7);
    std::normal_distribution<double> noise(0.0, 1e-9);
    const double w = 2.0 * std::numbers::pi * 10.0;
    const auto n = std::llround(o_.phase_s * 1e4);
    const double nan = std::numeric_limits<double>::quiet_NaN();
    stream_start_ = clock::now();
    stream(n, 1, [&](std::int64_t k, double& u, double& y) {  // NaN y now and then
      u = 250.0 * std::sin(w * static_cast<double>(k) * 1e-4);
      y = k % 200 == 0 ? nan : model.forward(u) + noise(rng);
    });
    stream(n, 1, [&](std::int64_t, double& u, double& y) {  // constant input
      u = 12.0;
      y = 3e-8 + noise(rng);
    });
    model = truth_model;
    stream(n, 1, [&](std::int64_t k, double& u, double& y) {  // y stuck while u moves
      u = 250.0 * std::sin(w * static_cast<double>(k) * 1e-4);
      y = 1e-7;
    });
    settle();
    print_figures();
    check(seen_.valid_params == 0, "garbage produced a valid HX_PARAMS");
    check(seen_.invalid_params == 0, "a valid = false set was published without --publish-invalid");
    check(counter("refits_accepted") == 0, "status counts an accepted refit");
    check(counter("refits_rejected_poisoned_window") >= 2, "poisoned windows not counted (NaN, dropout)");
    check(counter("refits_rejected_constant_input") >= 1, "constant input not refused");
    check(counter("non_finite") > 0 && counter("sensor.rejected_non_finite") > 0, "NaN samples not counted");
    check(counter("dropouts") >= 1, "stuck y not counted as a dropout");
    check(counter("seq_gaps") == 0, "refused blocks counted as a gap (or ticks lost)");
    check(counter("params_version") == 1, "the set in use changed");
    for (const auto& [name, value] : seen_.counters) {
      if (name.rfind("refits_", 0) == 0 && value > 0)
        std::printf("reident_stream: %s = %lld\n", name.c_str(), static_cast<long long>(value));
    }
    return failures_ == 0 ? 0 : 1;
  }

  Options o_;
  ChannelNames names_;
  std::unique_ptr<lcm::LCM> lcm_;
  Publisher<sensor_block_t> sensor_;
  Publisher<command_block_t> command_pub_;
  Publisher<mem_params_t> params_pub_;
  Subscription<mem_params_t> params_;
  Subscription<service_status_t> status_;
  Observed seen_;
  MemModel other_axes_{MemParams{0.8 * o_.c1, 0.8 * o_.c2, o_.c3}};  // the axes not under test (--axis y|z)
  sensor_block_t block_{};
  command_block_t commands_{};
  std::int64_t seq_ = 0;        // next sensor tick
  std::int64_t commanded_ = 0;  // next tick without a command
  int failures_ = 0;            // of check()
  clock::time_point stream_start_ = clock::now();
};

}  // namespace
}  // namespace hystloop

int main(int argc, char** argv) {
  return hystloop::probe::run_probe(
      "reident_stream",
      [&] {
        hystloop::Stream stream(hystloop::parse(argc, argv));
        return stream.run();
      },
      1);
}
