#include "lcm/control_filter.hpp"

#include <algorithm>

namespace hystloop {

bool ControlFilter::accept(const control_t& msg) noexcept {
  if (!msg.target.empty() && msg.target != process_) return false;
  if (std::find(seen_.begin(), seen_.end(), msg.request_id) != seen_.end()) return false;
  seen_[next_] = msg.request_id;
  next_ = (next_ + 1) % seen_.size();
  return true;
}

}  // namespace hystloop
