// The compensator service's references: trajectories (HX_TRAJECTORY) and scans (HX_SCAN, or the
// configured one) handed to the axes' control laws, and their verdicts.
#include <algorithm>
#include <cmath>
#include <limits>
#include <string_view>

#include <spdlog/spdlog.h>

#include "compensator/compensator_service.hpp"
#include "compensator/scan_message.hpp"
#include "compensator/trajectory_message.hpp"
#include "core/clock.hpp"
#include "core/periodic_timer.hpp"
#include "core/process.hpp"
#include "lcm/blocks.hpp"
#include "lcm/feedforward_mode.hpp"
#include "lcm/status_counters.hpp"
#include "models/model_descriptors.hpp"

namespace hystloop {

namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
}  // namespace

void CompensatorService::take_configured_scan() {
  scan_taken_ = true;
  const double start_s = static_cast<double>(x().last_seq()) * x().config().dt_s + settings_.scan.start_after_s;
  try {
    spdlog::info("{}", take_scan(settings_.scan, start_s));
  } catch (const std::exception& e) {
    spdlog::error("the configured scan was refused: {}", e.what());
  }
}

std::string CompensatorService::take_scan(const ScanSettings& scan, double start_s) {
  try {
    // One corner for every axis (x's stage model decides it): the axes run one path.
    const double corner_s = raster_corner_s(scan.raster, x().stage());
    const double check_s = scan_check_s(scan, corner_s);
    if (check_s * settings_.axes > kScanCheckBudget_s) {
      throw ParameterError("scan", fmt::format("runs {:.3g} s on each of {} axes; a scan is checked whole before it is "
                                               "taken, on the compensator's one thread, at most {} s of loop time over "
                                               "all axes (the bridge holds {} s of commands meanwhile): split it",
                                               check_s, settings_.axes, kScanCheckBudget_s,
                                               static_cast<double>(x().config().horizon_ticks) * x().config().dt_s));
    }
    std::vector<ScanShare> shares;
    std::vector<Compensator*> laws;
    for (int a = 0; a < settings_.axes; ++a) {
      shares.push_back(scan_share(scan, settings_.decoupling, a, start_s, corner_s));
      laws.push_back(&*laws_[static_cast<std::size_t>(a)]);
    }
    take_scan_on_every_axis(laws, shares, scan.blend_s);
    ++counters_.scans;
    return fmt::format("scan taken by {} axes{}: from loop time {:.4f} s to {:.4f} s", settings_.axes,
                       scan.decouple && settings_.axes > 1 ? ", decoupled" : "", start_s, shares[0].end_s());
  } catch (...) {
    ++counters_.scans_refused;
    throw;
  }
}

bool CompensatorService::scan_running() const noexcept {
  for (int a = 0; a < settings_.axes; ++a) {
    const Compensator& c = *laws_[static_cast<std::size_t>(a)];
    const double next_s = static_cast<double>(std::max<std::int64_t>(c.next_tick(), 0)) * c.config().dt_s;
    if (c.scan() != nullptr && next_s < c.scan()->end_s()) return true;
  }
  return false;
}

void CompensatorService::on_scan(const scan_t& msg) {
  if (msg.version == trajectory_version_ || msg.version == refused_version_) {  // UDP repeats: decided once
    ++counters_.trajectory_repeats;
    return;
  }
  try {
    if (!have_sample_) {
      throw ParameterError("scan", "no sensor block yet: where the axes are, and the loop time, are not known");
    }
    const ScanSettings scan = scan_from_message(msg, settings_.axes, x().stage());
    const Compensator& c = x();
    const double dt_s = c.config().dt_s;
    const double earliest_s = static_cast<double>(std::max<std::int64_t>(c.next_tick(), 0)) * dt_s + scan.blend_s;
    const double start_s =
        msg.start_utime == 0 ? earliest_s : loop_time_of_utime(msg.start_utime, last_sample_utime_, c.last_seq(), dt_s);
    const std::string note = take_scan(scan, start_s);
    trajectory_version_ = msg.version;
    ++counters_.trajectories;
    decide_trajectory(msg.version, note, false, false);
    if (const LogLimiter::Gate g = log_limiter_.allow(kLogTrajectory, monotonic_ns())) {
      spdlog::info("scan v{}: {}{}", msg.version, note, suppressed_note(g));
    }
  } catch (const std::exception& e) {
    ++counters_.trajectory_refused;
    refused_version_ = msg.version;
    decide_trajectory(msg.version, e.what(), true, false);
    if (const LogLimiter::Gate g = log_limiter_.allow(kLogTrajectoryRefused, monotonic_ns())) {
      spdlog::warn("scan v{} refused: {}{}", msg.version, escape_wire(e.what(), 600), suppressed_note(g));
    }
  }
  report_if_due();
}

Compensator& CompensatorService::law(int axis, const char* field) {
  if (axis < 0 || axis >= settings_.axes) {
    ++counters_.wrong_axis;
    throw ParameterError(field, "names axis " + std::string(axis_name(axis)) + ", but this stage has " +
                                    (settings_.axes == 1 ? std::string("only x (compensator.axes 1)")
                                                         : std::to_string(settings_.axes) + " axes"));
  }
  return *laws_[static_cast<std::size_t>(axis)];
}

void CompensatorService::apply_trajectory(TrajectorySpec spec, std::int64_t start_utime, std::int64_t version, int axis,
                                          bool check_elsewhere) {
  Compensator& c = law(axis, "trajectory.axis");
  if (settings_.axes > 1 && scan_running()) {
    // One axis leaving the path would leave the others following their shares of a motion that no
    // longer happens (each share holds the others' coupling).
    throw ParameterError("trajectory", "a scan is running on every axis: wait for its end (or send a scan)");
  }
  double start_s = kNaN;
  if (start_utime == 0) {
    pending_trajectory_.reset();  // a newer trajectory replaces one waiting for the first sample
  } else if (!have_sample_) {
    spec.validate();
    pending_trajectory_ = spec;
    pending_start_utime_ = start_utime;
    pending_version_ = version;
    pending_axis_ = axis;
    checking_version_ = version;  // its repeats wait with it
    return;
  } else {
    start_s = loop_time_of_utime(start_utime, last_sample_utime_, c.last_seq(), c.config().dt_s);
  }
  // Before the first sample the bridge holds no commands of ours; inline, as configured.
  if (!check_elsewhere || !have_sample_ || !settings_.check_on_thread) {
    taken(c.take_trajectory(spec, start_s), version, spec);
    return;
  }
  spec.validate();  // what is refused at once needs no thread
  checking_version_ = version;
  std::optional<TrajectoryChecker::Request> replaced =
      checker_.submit({c.plan_snapshot(), spec, start_s, c.learner().enabled(), version, axis, law_epoch_});
  if (replaced) {
    refuse_trajectory(replaced->version, fmt::format("superseded by trajectory {} before it was checked", version));
  }
}

void CompensatorService::take_checked_trajectories() {
  bool decided = false;
  while (std::optional<TrajectoryChecker::Outcome> o = checker_.poll()) {
    decided = true;
    try {
      if (o->epoch != law_epoch_) {
        throw ParameterError("trajectory", "the bridge restarted while it was checked: send it again");
      }
      if (!o->verdict) {  // the check's own words (ParameterError's, its field named)
        law(o->axis, "trajectory.axis").count_refused_trajectory();
        refuse_trajectory(o->version, o->refusal);
        continue;
      }
      if (settings_.axes > 1 && scan_running()) {
        throw ParameterError("trajectory", "a scan started on every axis while it was checked: wait for its end");
      }
      taken(law(o->axis, "trajectory.axis").commit_trajectory(std::move(*o->verdict), o->start_s), o->version, o->spec);
    } catch (const std::exception& e) {
      refuse_trajectory(o->version, e.what());
    }
  }
  if (decided) report_if_due();
}

void CompensatorService::taken(const TrajectoryVerdict& v, std::int64_t version, const TrajectorySpec& requested) {
  if (!v.started) ++counters_.trajectory_late_start;
  ++counters_.trajectories;
  trajectory_version_ = version;
  decide_trajectory(version, v.note, false, v.shaped);
  if (version <= 0) return;  // the configured reference: logged at the start
  if (const LogLimiter::Gate g = log_limiter_.allow(kLogTrajectory, monotonic_ns())) {
    spdlog::info("trajectory v{}: shape {}, amplitude {:.4g} m, offset {:.4g} m, {} Hz, blend {} s{}", version,
                 static_cast<int>(requested.shape), requested.amplitude_m, requested.offset_m, requested.frequency_hz,
                 requested.blend_s, suppressed_note(g));
    if (!verdict_.empty()) spdlog::info("{}", verdict_);
  }
}

void CompensatorService::refuse_trajectory(std::int64_t version, const std::string& why) {
  ++counters_.trajectory_refused;
  refused_version_ = version;  // its repeats are the same refusal
  decide_trajectory(version, why, true, false);
  if (const LogLimiter::Gate g = log_limiter_.allow(kLogTrajectoryRefused, monotonic_ns())) {
    spdlog::warn("trajectory v{} refused: {}{}", version, escape_wire(why, 600), suppressed_note(g));
  }
}

void CompensatorService::settle_trajectories() {
  while (checker_.busy()) {
    checker_.wait_ready();
    take_checked_trajectories();
  }
}

void CompensatorService::decide_trajectory(std::int64_t version, const std::string& verdict, bool refused,
                                           bool shaped) {
  if (version <= 0) return;  // the configured reference: nobody waits for it
  if (refused) {
    counters_.trajectory_refused_version = version;
    // The compensator's own words (the limit, what would fit): whole, not cut like wire text.
    constexpr std::size_t kVerdictChars = 600;
    verdict_ = fmt::format("trajectory {} refused: {}", version, escape_wire(verdict, kVerdictChars));
  } else {
    counters_.trajectory_version = version;
    if (shaped) counters_.trajectory_shaped_version = version;
    verdict_ = verdict.empty() ? std::string()
                               : fmt::format("trajectory {} {}: {}", version, shaped ? "shaped" : "taken", verdict);
  }
  verdict_until_ns_ = monotonic_ns() + 10'000'000'000;  // 10 s in the status detail
  verdict_due_ = true;                                  // answered at once, not at the next second
}

void CompensatorService::on_trajectory(const trajectory_t& msg) {
  // UDP repeats: decided once (or being decided)
  if (msg.version == trajectory_version_ || msg.version == refused_version_ || msg.version == checking_version_) {
    ++counters_.trajectory_repeats;
    return;
  }
  try {
    apply_trajectory(trajectory_from_message(msg), msg.start_utime, msg.version, msg.axis);
  } catch (const std::exception& e) {
    refuse_trajectory(msg.version, e.what());
  }
  report_if_due();
}

}  // namespace hystloop
