#include "params_publish.hpp"

#include <algorithm>
#include <limits>
#include <thread>

#include "adoption_watch.hpp"
#include "core/errors.hpp"
#include "core/process.hpp"
#include "hystloop/command_block_t.hpp"
#include "hystloop/service_status_t.hpp"
#include "lcm/blocks.hpp"
#include "lcm/connection.hpp"
#include "lcm/publisher.hpp"
#include "lcm/subscription.hpp"
#include "lcm/url.hpp"
#include "loop/params_admission.hpp"
#include "runtime/model_params_message.hpp"

namespace hystloop {

void PublishOptions::validate() const {
  if (version && *version < 1) throw ParameterError("version", "must be >= 1 (got " + std::to_string(*version) + ")");
  require_in_range("listen_s", listen_s, 0.0, 60.0);
  if (repeats < 1 || repeats > 10) {
    throw ParameterError("repeats", "must be 1..10 (got " + std::to_string(repeats) + ")");
  }
  validate_rig_prefix(rig);
  require_in_range("timeout", timeout_s, 0.0, 600.0);
  if (compensator.empty()) throw ParameterError("compensator", "must name the compensator's process");
}

std::int32_t next_params_version(std::int32_t highest_heard) noexcept {
  if (highest_heard >= std::numeric_limits<std::int32_t>::max()) return highest_heard;
  return std::max(highest_heard + 1, 2);
}

mem_params_t to_mem_params(const MemFitResult& fit, double window_s, std::int32_t version, std::int64_t utime_us,
                           const std::string& source) {
  mem_params_t m{};
  m.utime = utime_us;
  m.version = version;
  m.publisher_id = process_publisher_id();  // each run is a new publisher: its version is never "stale"
  m.c1 = fit.params.c1;
  m.c2 = fit.params.c2;
  m.c3 = fit.params.c3;
  m.residual_m = fit.residual_rms_m;
  m.samples_used = static_cast<std::int64_t>(fit.samples_used);
  m.window_s = window_s;
  m.valid = static_cast<std::int8_t>(fit.ok() ? 1 : 0);
  m.source = source;
  return m;
}

model_params_t to_model_params(const ModelParamSet& set, const FitFigures& fit, std::int32_t version,
                               std::int64_t utime_us, const std::string& source) {
  model_params_t m{};
  set_model(m, set);
  m.utime = utime_us;
  m.version = version;
  m.publisher_id = process_publisher_id();  // one sequence per run over HX_PARAMS and HX_MODEL
  m.residual_m = fit.residual_m;
  m.heldout_rms_m = fit.heldout_rms_m;
  m.samples_used = static_cast<std::int64_t>(fit.samples_used);
  m.window_s = fit.window_s;
  m.valid = true;
  m.stage_kind = model_params_t::STAGE_UNCHANGED;
  m.source = source;
  return m;
}

std::string identify_source() { return "hystloop-identify@" + host_name(); }

ParamsLink::ParamsLink(const PublishOptions& options)
    : options_(options), channels_(options.rig), url_(resolve_lcm_url(options.lcm_url, options.allow_network)) {
  options_.validate();
  lcm_ = open_lcm(url_, options_.allow_network);
}

std::int32_t ParamsLink::highest_version_heard() {
  std::int32_t highest = 0;
  Subscription<mem_params_t> params(
      *lcm_, channels_.params, [&](const mem_params_t& p, std::int64_t) { highest = std::max(highest, p.version); });
  Subscription<model_params_t> models(
      *lcm_, channels_.model, [&](const model_params_t& p, std::int64_t) { highest = std::max(highest, p.version); });
  Subscription<command_block_t>::Options queue;
  queue.queue_capacity = 4'000;  // blocks of the whole listening time
  Subscription<command_block_t> commands(
      *lcm_, channels_.command,
      [&](const command_block_t& c, std::int64_t) {
        for_each_tick(c, [&](const CommandTick& t) { highest = std::max(highest, t.params_version); });
      },
      queue);
  using Clock = std::chrono::steady_clock;
  const auto deadline =
      Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(options_.listen_s));
  for (auto now = Clock::now(); now < deadline; now = Clock::now()) {
    const auto left = std::chrono::duration_cast<std::chrono::microseconds>(deadline - now);
    if (handle_pending(*lcm_, std::min(left, std::chrono::microseconds(50'000)), 1024) < 0) break;
  }
  return highest;
}

namespace {

template <class T>
int publish_repeated(lcm::LCM& lcm, const std::string& channel, const T& msg, const PublishOptions& options) {
  Publisher<T> publisher(lcm, channel);
  int sent = 0;
  for (int i = 0; i < options.repeats; ++i) {
    if (i > 0) std::this_thread::sleep_for(options.gap);
    if (publisher.publish(msg)) ++sent;
    if (publisher.counters().invalid > 0) return 0;  // refused by the contract: never retried
  }
  return sent;
}

}  // namespace

int ParamsLink::publish(mem_params_t msg) {
  msg.axis = static_cast<std::int8_t>(options_.axis);
  return publish_repeated(*lcm_, channels_.params, msg, options_);
}

int ParamsLink::publish(model_params_t msg) {
  msg.axis = static_cast<std::int8_t>(options_.axis);
  return publish_repeated(*lcm_, channels_.model, msg, options_);
}

ParamsLink::Adoption ParamsLink::wait_for_adoption(std::int32_t version) {
  AdoptionWatch watch(options_.compensator, version, options_.axis);
  Subscription<service_status_t> status(*lcm_, channels_.status,
                                        [&](const service_status_t& s, std::int64_t) { watch.on_status(s); });
  Subscription<command_block_t>::Options queue;
  queue.queue_capacity = 4'000;
  Subscription<command_block_t> commands(
      *lcm_, channels_.command,
      [&](const command_block_t& c, std::int64_t) {
        const auto axis = static_cast<std::size_t>(options_.axis);
        if (c.n_ticks > 0 && axis < axes_of(c)) {
          watch.on_command_version(command_tick(c, static_cast<std::size_t>(c.n_ticks - 1), axis).params_version);
        }
      },
      queue);
  using Clock = std::chrono::steady_clock;
  const auto start = Clock::now();
  const auto deadline =
      start + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(options_.timeout_s));
  for (auto now = start; now < deadline && !watch.adopted(); now = Clock::now()) {
    const auto left = std::chrono::duration_cast<std::chrono::microseconds>(deadline - now);
    if (handle_pending(*lcm_, std::min(left, std::chrono::microseconds(50'000)), 1024) < 0) break;
  }
  return {watch.adopted(), watch.verdict(options_.timeout_s, channels_.status)};
}

}  // namespace hystloop
