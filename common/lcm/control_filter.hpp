#pragma once
// Which control_t requests a process acts on: those addressed to it (or to every
// process), each request_id once — senders repeat a request over UDP.

#include <array>
#include <cstdint>
#include <string>

#include "hystloop/control_t.hpp"

namespace hystloop {

class ControlFilter {
 public:
  explicit ControlFilter(std::string process) : process_(std::move(process)) {}

  // True the first time a request for this process arrives.
  bool accept(const control_t& msg) noexcept;

 private:
  std::string process_;
  std::array<std::int64_t, 64> seen_{};  // recent request ids (ring)
  std::size_t next_ = 0;
};

}  // namespace hystloop
