#include "lcm/status_counters.hpp"

#include <cstddef>
#include <limits>
#include <string>

namespace hystloop {
namespace {

std::int64_t saturate(std::uint64_t value) {
  constexpr auto kMax = static_cast<std::uint64_t>(std::numeric_limits<std::int64_t>::max());
  return static_cast<std::int64_t>(value > kMax ? kMax : value);
}

std::string joined(std::string_view endpoint, std::string_view name) {
  std::string out(endpoint);
  out += '.';
  out += name;
  return out;
}

}  // namespace

void clear_counters(service_status_t& status) {
  status.counter_names.clear();
  status.counter_values.clear();
  status.n_counters = 0;
}

bool add_counter(service_status_t& status, std::string_view name, std::uint64_t value) {
  if (status.n_counters >= service_status_t::MAX_COUNTERS) return false;
  status.counter_names.emplace_back(name);
  status.counter_values.push_back(saturate(value));
  status.n_counters = static_cast<std::int32_t>(status.counter_names.size());
  return true;
}

bool add_endpoint_counters(service_status_t& status, std::string_view endpoint, const EndpointCounters& counters) {
  bool ok = add_counter(status, joined(endpoint, "received"), counters.received);
  ok = add_counter(status, joined(endpoint, "accepted"), counters.accepted) && ok;
  for (std::size_t i = 0; i < kRejectReasonCount; ++i) {
    const auto reason = static_cast<RejectReason>(i);
    ok = add_counter(status, joined(endpoint, "rejected_" + std::string(to_string(reason))),
                     counters.rejected(reason)) &&
         ok;
  }
  status.rejected = saturate(static_cast<std::uint64_t>(status.rejected) + counters.rejected_total());
  return ok;
}

bool add_publisher_counters(service_status_t& status, std::string_view endpoint, const PublisherCounters& counters) {
  bool ok = add_counter(status, joined(endpoint, "published"), counters.published);
  ok = add_counter(status, joined(endpoint, "invalid"), counters.invalid) && ok;
  ok = add_counter(status, joined(endpoint, "encode_failed"), counters.encode_failed) && ok;
  ok = add_counter(status, joined(endpoint, "transport_failed"), counters.transport_failed) && ok;
  return ok;
}

std::optional<std::int64_t> find_counter(const service_status_t& status, std::string_view name) {
  for (std::size_t i = 0; i < status.counter_names.size() && i < status.counter_values.size(); ++i) {
    if (status.counter_names[i] == name) return status.counter_values[i];
  }
  return std::nullopt;
}

std::string axis_counter_name(std::string_view name, int axis) {
  if (axis <= 0 || axis >= 3) return std::string(name);
  return std::string(1, "xyz"[axis]) + "_" + std::string(name);
}

std::string params_version_counter(int axis) { return axis_counter_name("params_version", axis); }

}  // namespace hystloop
