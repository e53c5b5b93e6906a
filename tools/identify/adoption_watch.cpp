#include "adoption_watch.hpp"

#include <algorithm>
#include <array>

#include "core/errors.hpp"
#include "lcm/status_counters.hpp"

namespace hystloop {
namespace {

// The compensator's counters of sets it did not take (services/compensator: admit, offer, on_model).
constexpr std::array<const char*, 5> kRefusalCounters{"params_rejected", "params_invalid", "params_stale",
                                                      "model_unknown_kind", "model_unknown_format"};

}  // namespace

AdoptionWatch::AdoptionWatch(std::string compensator_process, std::int32_t published_version, int axis)
    : compensator_(std::move(compensator_process)),
      version_(published_version),
      counter_(params_version_counter(axis)) {}

void AdoptionWatch::on_status(const service_status_t& status) {
  heard_.insert(status.process);
  if (status.process != compensator_) return;
  compensator_heard_ = true;
  if (const auto v = find_counter(status, counter_)) status_version_ = *v;
  for (const char* name : kRefusalCounters) {
    if (const auto v = find_counter(status, name)) {
      refusals_first_.try_emplace(name, *v);
      refusals_last_[name] = *v;
    }
  }
}

void AdoptionWatch::on_command_version(std::int32_t params_version) { command_version_ = params_version; }

std::optional<std::int64_t> AdoptionWatch::version_in_use() const noexcept {
  return status_version_ ? status_version_ : command_version_;
}

bool AdoptionWatch::adopted() const noexcept { return version_in_use() == std::int64_t{version_}; }

std::string AdoptionWatch::verdict(double waited_s, const std::string& status_channel) const {
  const std::string who = "'" + compensator_ + "'";
  if (adopted()) return "adopted by " + who + " (version " + std::to_string(*version_in_use()) + ")";
  if (heard_.empty() && !command_version_) {
    return "no rig is running (nothing reported on " + status_channel + " within " + number_text(waited_s, 3) + " s)";
  }
  std::string why = "not adopted within " + number_text(waited_s, 3) + " s (";
  if (const auto v = version_in_use()) {
    why += who + " in use: version " + std::to_string(*v);
  } else if (compensator_heard_) {
    why += who + " reported no version in use";
  } else {
    why += "no " + who + " reported on " + status_channel + "; heard:";
    for (const auto& p : heard_) why += " " + p;
  }
  for (const auto& [name, last] : refusals_last_) {
    const std::int64_t rose = last - refusals_first_.at(name);
    if (rose > 0) why += "; its " + name + " rose by " + std::to_string(rose);
  }
  return why + ")";
}

}  // namespace hystloop
