#pragma once
// Reads the events of one LCM event log file, and says what else the file held.
//
// lcm::LogFile (liblcm 1.3) stops at the first damage: an event followed by anything but the
// next sync word is dropped with "Invalid header after log data" on stderr and reading ends,
// so one torn write loses the rest of the file without a count; random bytes are "no events";
// a garbage length can ask for a 2 GB buffer. This reader keeps going instead: it looks for
// the next sync word, accepts an event only when its lengths fit the file (channel 1..999
// bytes, data within what is left), and counts the bytes that were not events.
// Format (big-endian): sync 0xEDA1DA01, event number (8), timestamp [us] (8), channel length
// (4), data length (4), channel, data.

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "run_data.hpp"

namespace hystloop::report {

class EventFileReader {
 public:
  // Throws std::runtime_error naming the file if it is not a regular file or cannot be opened.
  explicit EventFileReader(const std::filesystem::path& file);
  ~EventFileReader();
  EventFileReader(const EventFileReader&) = delete;
  EventFileReader& operator=(const EventFileReader&) = delete;

  // The next complete event (valid until the next call), or nullptr at the end of the file.
  const lcm::LogEvent* next();
  // Events read and bytes that were not events so far (complete once next() returned nullptr).
  const LogFileScan& scan() const noexcept { return scan_; }

 private:
  bool read_exact(void* out, std::size_t n);

  std::FILE* file_ = nullptr;
  LogFileScan scan_;
  std::uint64_t end_of_last_ = 0;  // file offset just after the last complete event
  std::string channel_;
  std::vector<std::uint8_t> data_;
  lcm::LogEvent event_{};
};

}  // namespace hystloop::report
