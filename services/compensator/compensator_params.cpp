// The compensator's parameter inputs: HX_PARAMS (mem_params_t, MEM parameters for the MEM
// inverse; the mode does not change) and HX_MODEL (model_params_t, any model: the feedforward
// switches to it at the next reversal, re-anchored). Both go through one admission path: a
// diagnostic set (valid = false) is counted and dropped, versions are ordered per publisher over
// both channels (ParamsAdmission), and the set is validated again here (ModelParamSet::validate
// via the control law) before it is offered, and against the rig: a set whose small-signal gain
// over the actuator's range leaves [linear.gain / F, linear.gain * F], or with a subnormal parameter,
// is refused as params_rejected with the reason (models/gain_plausibility.hpp, F =
// compensator.plausible_gain_factor): a units error or a corrupted set never reaches the
// actuator, whatever its model's own domain allows. HX_MODEL's own refusals: a kind or format version
// this build does not know (model_unknown_kind, model_unknown_format; the Subscription lets them
// through its envelope check so that they are counted by their reason here). A publisher whose
// sets keep being refused as stale below the version accepted from it is frozen out
// (ParamsAdmission::frozen): HX_STATUS says DEGRADED, naming it (report()).
#include <spdlog/spdlog.h>

#include "compensator/compensator_service.hpp"
#include "core/errors.hpp"
#include "core/periodic_timer.hpp"
#include "models/gain_plausibility.hpp"
#include "models/model_descriptors.hpp"
#include "runtime/model_params_message.hpp"

namespace hystloop {

bool CompensatorService::admit(const ParamsHeader& h) {
  // Each refusal is counted; it is logged once per reason and publisher (ParamsAdmission), and
  // of those at most one line per reason a second (many publishers: forged ids).
  const auto log_refusal = [&](ParamsRefusal reason, LogReason line) {
    if (!admission_.first_refusal(h.publisher_id, reason)) return LogLimiter::Gate{};
    return log_limiter_.allow(line, monotonic_ns());
  };
  const auto from = static_cast<std::uint64_t>(h.publisher_id);
  if (!h.valid) {
    ++counters_.params_invalid;
    if (const LogLimiter::Gate g = log_refusal(ParamsRefusal::invalid, kLogParamsInvalid)) {
      spdlog::warn(
          "{} parameters v{} from '{}' (publisher {:x}) are marked invalid; not used (further invalid "
          "sets from this publisher are counted, params_invalid, not logged){}",
          h.what, h.version, escape_wire(h.source), from, suppressed_note(g));
    }
    return false;
  }
  if (!admission_.is_new(h.publisher_id, h.version)) {
    ++counters_.params_stale;
    // Below the version accepted from it (not a repeat of that one): counts toward frozen out.
    if (admission_.refuse_stale(h.publisher_id, h.version, monotonic_ns())) {
      ++counters_.params_stale_below;
    } else {
      ++counters_.params_stale_repeat;
    }
    if (const LogLimiter::Gate g = log_refusal(ParamsRefusal::stale, kLogParamsStale)) {
      spdlog::info(
          "{} parameters v{} from '{}' (publisher {:x}) ignored: not newer than v{} accepted from it "
          "(further stale sets from this publisher are counted, params_stale, not logged){}",
          h.what, h.version, escape_wire(h.source), from, admission_.last_version(h.publisher_id), suppressed_note(g));
    }
    return false;
  }
  return true;
}

void CompensatorService::offer(const ParamsHeader& h, const ModelParamSet& set, bool switch_model) {
  const auto from = static_cast<std::uint64_t>(h.publisher_id);
  try {
    require_plausible(set, gain_plausibility(settings_));
    Compensator& c = law(h.axis, "params.axis");  // a set models one axis's actuator
    if (switch_model) {
      c.offer_model(set, h.version);
    } else {
      c.offer_mem_params(set.mem, h.version);
    }
    admission_.accept(h.publisher_id, h.version);
    if (const LogLimiter::Gate g = log_limiter_.allow(kLogParamsAccepted, monotonic_ns())) {
      spdlog::info(
          "{} parameters v{} from '{}' (publisher {:x}) accepted{} ({}; residual {:.3g} m); swapped in at the "
          "next reversal{}",
          h.what, h.version, escape_wire(h.source), from,
          settings_.axes > 1 ? " for " + std::string(axis_name(h.axis)) : std::string(), describe_model(set),
          h.residual_m, suppressed_note(g));
    }
  } catch (const ParameterError& e) {
    ++counters_.params_refused;
    if (!admission_.first_refusal(h.publisher_id, ParamsRefusal::refused)) return;
    if (const LogLimiter::Gate g = log_limiter_.allow(kLogParamsRefused, monotonic_ns())) {
      spdlog::warn(
          "{} parameters v{} from '{}' (publisher {:x}) refused: {} (further refusals from this publisher "
          "are counted, params_rejected, not logged){}",
          h.what, h.version, escape_wire(h.source), from, e.what(), suppressed_note(g));
    }
  }
}

void CompensatorService::on_params(const mem_params_t& msg) {
  const ParamsHeader h{"MEM", msg.version, msg.publisher_id, msg.valid != 0, msg.source, msg.residual_m, msg.axis};
  if (admit(h)) offer(h, model_from_message(msg), false);
}

void CompensatorService::on_model(const model_params_t& msg) {
  const std::optional<ModelKind> kind = model_kind_from_int(msg.kind);
  const std::string_view what = kind ? to_string(*kind) : std::string_view("model");
  const ParamsHeader h{what, msg.version, msg.publisher_id, msg.valid != 0, msg.source, msg.residual_m, msg.axis};
  const bool format_known = msg.format_version == model_params_t::FORMAT_VERSION;
  const std::optional<ModelParamSet> set = format_known ? model_from_message(msg) : std::nullopt;
  if (!set) {
    std::uint64_t& count = format_known ? counters_.model_unknown_kind : counters_.model_unknown_format;
    ++count;
    if (const LogLimiter::Gate g = log_limiter_.allow(kLogModelUnknown, monotonic_ns())) {
      spdlog::warn(
          "model parameters v{} from '{}' (publisher {:x}) refused: {} {} is not one this build knows "
          "(counted, {}){}",
          msg.version, escape_wire(msg.source), static_cast<std::uint64_t>(msg.publisher_id),
          format_known ? "kind" : "format version", format_known ? msg.kind : msg.format_version,
          format_known ? "model_unknown_kind" : "model_unknown_format", suppressed_note(g));
    }
    return;
  }
  if (admit(h)) offer(h, *set, true);
}

}  // namespace hystloop
