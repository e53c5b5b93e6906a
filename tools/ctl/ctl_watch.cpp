#include "ctl_watch.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

#include <spdlog/fmt/fmt.h>

#include "ctl_health.hpp"
#include "lcm/blocks.hpp"
#include "models/axis_coupling.hpp"

namespace hystloop::ctl {

void ErrorStats::add(double e_m) noexcept {
  ++count;
  sum_sq_m2 += e_m * e_m;
  max_abs_m = std::max(max_abs_m, std::abs(e_m));
}

std::optional<double> ErrorStats::rms_m() const noexcept {
  if (count == 0) return std::nullopt;
  return std::sqrt(sum_sq_m2 / static_cast<double>(count));
}

void WatchSecond::add_sensor_block(const sensor_block_t& block, std::size_t axis) noexcept {
  if (axis >= axes_of(block)) return;
  bool armed = true;
  for_each_tick(
      block,
      [&](const SensorTick& t) {
        ++samples;
        if (std::isfinite(t.y_ref_m)) error.add(t.y_ref_m - t.y_m);
        armed = armed && (t.flags & sensor_block_t::SAFE_STATE) == 0;
      },
      axis);
  if (armed) buffer_min_ticks = std::min(buffer_min_ticks.value_or(block.buffer_depth_ticks), block.buffer_depth_ticks);
}

void TruthPairing::pair(const std::vector<double>& y_ref, const std::vector<double>& y_true,
                        WatchSecond& into) noexcept {
  if (y_ref.size() != y_true.size()) return;  // not the same block after all
  for (std::size_t i = 0; i < y_ref.size(); ++i) {
    if (std::isfinite(y_ref[i]) && std::isfinite(y_true[i])) into.true_error.add(y_ref[i] - y_true[i]);
  }
}

void TruthPairing::keep(std::deque<Block>& waiting, Block block) {
  if (waiting.size() == kWaiting) waiting.pop_front();
  waiting.push_back(std::move(block));
}

void TruthPairing::add_sensor_block(const sensor_block_t& block, WatchSecond& into) {
  if (axis_ >= axes_of(block)) return;
  Block b{block.seq, {}};
  b.y_m.reserve(static_cast<std::size_t>(std::max(block.n_ticks, 0)));
  for_each_tick(
      block, [&](const SensorTick& t) { b.y_m.push_back(t.y_ref_m); }, axis_);
  const auto match = std::find_if(truths_.begin(), truths_.end(), [&](const Block& t) { return t.seq == b.seq; });
  if (match == truths_.end()) return keep(refs_, std::move(b));
  pair(b.y_m, match->y_m, into);
  truths_.erase(match);
}

void TruthPairing::add_truth_block(const sim_truth_t& truth, WatchSecond& into) {
  const auto match = std::find_if(refs_.begin(), refs_.end(), [&](const Block& r) { return r.seq == truth.seq; });
  std::vector<double> y_true = axis_truth(truth, axis_);
  if (match == refs_.end()) return keep(truths_, Block{truth.seq, std::move(y_true)});
  pair(match->y_m, y_true, into);
  refs_.erase(match);
}

std::string axis_counter(std::string_view name, int axis) {
  std::string out = axis == 0 ? std::string() : std::string(axis_name(axis)) + "_";
  out.append(name);
  return out;
}

std::optional<double> learning_rms_nm(const service_status_t& compensator, int axis) {
  if (const auto nm = find_counter(compensator, axis_counter("learning_rms_nm", axis))) return static_cast<double>(*nm);
  if (const auto pm = find_counter(compensator, axis_counter("learning_rms_pm", axis))) {
    return static_cast<double>(*pm) * 1e-3;
  }
  return std::nullopt;
}

std::string format_watch_line(const WatchLine& l) {
  std::string out = fmt::format("{:5.0f} s", l.elapsed_s);
  if (const auto rms = l.second.error.rms_m()) {
    out += fmt::format("  rms {:7.1f} nm  max {:7.1f} nm", *rms * 1e9, l.second.error.max_abs_m * 1e9);
  } else {
    out += fmt::format("  rms {:>7} nm  max {:>7} nm", "--", "--");
  }
  if (const auto true_rms = l.second.true_error.rms_m()) {
    out += fmt::format("  true {:.2f} nm max {:.1f} nm", *true_rms * 1e9, l.second.true_error.max_abs_m * 1e9);
  }
  out += fmt::format("  ticks {:6}/{}", l.second.error.count, l.second.samples);
  out += l.params_in_use ? "  params v" + std::to_string(*l.params_in_use) : std::string("  params --");
  if (l.params_latest && l.params_latest != l.params_in_use)
    out += " (v" + std::to_string(*l.params_latest) + " published)";
  out += l.late_total ? fmt::format("  late {} (+{})", *l.late_total, l.late_delta.value_or(0)) : "  late --";
  out += l.clamped_per_s ? "  clamped " + std::to_string(*l.clamped_per_s) + "/s" : std::string("  clamped --");
  out += l.second.buffer_min_ticks ? "  buf min " + std::to_string(*l.second.buffer_min_ticks)
                                   : std::string("  buf min --");
  out += l.bridge_state.empty() ? "  bridge --" : "  bridge " + l.bridge_state;
  if (l.learning_rms_nm || l.learning_periods) {
    out += l.learning_rms_nm ? fmt::format("  learned {:.1f} nm", *l.learning_rms_nm) : "  learned -- nm";
    out += " (" + (l.learning_periods ? std::to_string(*l.learning_periods) : std::string("--")) + " periods)";
  }
  const std::int64_t refused = l.trajectories_refused.value_or(0), shaped = l.trajectories_shaped.value_or(0);
  if (refused > 0 || shaped > 0) {
    out += "  trajectories refused " + std::to_string(refused) + ", shaped " + std::to_string(shaped);
  }
  return out;
}

}  // namespace hystloop::ctl
