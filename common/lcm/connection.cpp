#include "lcm/connection.hpp"

#include <poll.h>

#include <cerrno>
#include <ctime>
#include <stdexcept>
#include <string>

#include "lcm/url.hpp"

namespace hystloop {

std::unique_ptr<lcm::LCM> open_lcm(std::string_view url, bool allow_network) {
  const std::string checked = resolve_lcm_url(url, allow_network);
  auto lcm = std::make_unique<lcm::LCM>(checked);
  if (!lcm->good()) {
    throw std::runtime_error("LCM could not start on " + checked +
                             " (udpm needs a multicast route: run inside tools/netns-run, or see its --help)");
  }
  return lcm;
}

int handle_pending(lcm::LCM& lcm, std::chrono::microseconds timeout, int max_messages) noexcept {
  const int fd = lcm.getFileno();
  if (fd < 0) return -1;
  const auto wait_us = timeout.count() > 0 ? timeout.count() : 0;
  timespec ts{};
  ts.tv_sec = static_cast<time_t>(wait_us / 1000000);
  ts.tv_nsec = static_cast<long>((wait_us % 1000000) * 1000);
  pollfd pfd{fd, POLLIN, 0};
  const int ready = ppoll(&pfd, 1, &ts, nullptr);
  if (ready < 0) return errno == EINTR ? 0 : -1;  // a signal: let the caller look at its stop flag
  if (ready == 0) return 0;
  return dispatch_pending(lcm, max_messages);
}

int dispatch_pending(lcm::LCM& lcm, int max_messages) noexcept {
  int handled = 0;
  while (handled < max_messages) {
    const int rc = lcm.handleTimeout(0);  // dispatches one message if one is ready, never waits
    if (rc < 0) return -1;
    if (rc == 0) break;
    ++handled;
  }
  return handled;
}

}  // namespace hystloop
