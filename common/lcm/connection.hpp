#pragma once
// Opening LCM on a checked URL, and waiting for traffic without ever blocking longer than
// asked: a service's loop calls handle_pending() with its remaining time budget instead
// of LCM's blocking handle().

#include <chrono>
#include <memory>
#include <string_view>

#include <lcm/lcm-cpp.hpp>

namespace hystloop {

// LCM on `url` after checked_lcm_url(url, allow_network) (empty url: resolve_lcm_url).
// Throws ParameterError for a refused URL, std::runtime_error if LCM cannot start
// (for udpm often: no multicast route; run inside tools/netns-run).
std::unique_ptr<lcm::LCM> open_lcm(std::string_view url, bool allow_network = false);

// Waits up to `timeout` for a message, then dispatches what is pending, at most
// `max_messages`, without waiting again. Returns the number dispatched (0 on timeout) or
// -1 if LCM reported an error. Microsecond resolution (ppoll on LCM's file descriptor).
int handle_pending(lcm::LCM& lcm, std::chrono::microseconds timeout, int max_messages = 256) noexcept;

// Dispatches what is pending, at most `max_messages`, never waiting: for a loop that waits on
// LCM's file descriptor together with its own (the bridge's ppoll). Returns the number
// dispatched or -1 if LCM reported an error.
int dispatch_pending(lcm::LCM& lcm, int max_messages = 256) noexcept;

}  // namespace hystloop
