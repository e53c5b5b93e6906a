#pragma once
// Filling service_status_t's named counters from the endpoint counts (1 Hz, off the
// per-sample path: these build strings).

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "hystloop/service_status_t.hpp"
#include "lcm/reject_reason.hpp"

namespace hystloop {

// Empties the counter arrays (keeping their capacity).
void clear_counters(service_status_t& status);

// Appends one counter, keeping n_counters in step. Returns false (and adds nothing) when
// MAX_COUNTERS are already there. Values above INT64_MAX saturate.
bool add_counter(service_status_t& status, std::string_view name, std::uint64_t value);

// "<endpoint>.received", "<endpoint>.accepted", "<endpoint>.rejected_<reason>" for each reason.
// Adds `counters.rejected_total()` to status.rejected. Returns false if some did not fit.
bool add_endpoint_counters(service_status_t& status, std::string_view endpoint, const EndpointCounters& counters);

// "<endpoint>.published", ".invalid", ".encode_failed", ".transport_failed".
bool add_publisher_counters(service_status_t& status, std::string_view endpoint, const PublisherCounters& counters);

// The value of the named counter of a status message (as received: the arrays are trusted only
// as far as both reach); nullopt when it has none by that name.
std::optional<std::int64_t> find_counter(const service_status_t& status, std::string_view name);

// Axis `axis`'s name of a per-axis counter: `name` for x (0), "y_" + name, "z_" + name.
std::string axis_counter_name(std::string_view name, int axis);

// The compensator's counter of the parameter set in use on `axis` (0: x): "params_version" for x,
// "y_params_version" / "z_params_version" for the others (what a tool that publishes a set waits on).
std::string params_version_counter(int axis);

}  // namespace hystloop
