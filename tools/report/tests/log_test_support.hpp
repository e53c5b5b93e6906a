#pragma once
// What the end-to-end tests of hystloop-report and hystloop-export share: logs written with
// lcm::LogFile from encoded messages, files read back whole, and a tool run as a process with
// its stdout, stderr and exit status.
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <lcm/lcm-cpp.hpp>

namespace hystloop::test {

// One event of a log to be written: its receive time [us], channel and encoded message.
struct Event {
  std::int64_t t;
  std::string channel;
  std::vector<std::uint8_t> bytes;
};

template <class T>
Event event(std::int64_t t, const std::string& channel, const T& msg) {
  Event e{t, channel, std::vector<std::uint8_t>(static_cast<std::size_t>(msg.getEncodedSize()))};
  msg.encode(e.bytes.data(), 0, msg.getEncodedSize());
  return e;
}

inline void write_event(lcm::LogFile& log, Event& e) {
  lcm::LogEvent le{};
  le.timestamp = e.t;
  le.channel = e.channel;
  le.datalen = static_cast<std::int32_t>(e.bytes.size());
  le.data = e.bytes.data();
  ASSERT_EQ(log.writeEvent(&le), 0);
}

template <class T>
void write(lcm::LogFile& log, std::int64_t t, const std::string& channel, const T& msg) {
  Event e = event(t, channel, msg);
  write_event(log, e);
}

// Writes the events to `file` in time order (events of one time in the order given).
inline void write_events(const std::filesystem::path& file, std::vector<Event>& events) {
  std::stable_sort(events.begin(), events.end(), [](const Event& a, const Event& b) { return a.t < b.t; });
  lcm::LogFile log(file.string(), "w");
  ASSERT_TRUE(log.good());
  for (auto& e : events) write_event(log, e);
}

inline std::string slurp(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

inline bool is_png(const std::filesystem::path& path) {
  return slurp(path).substr(0, 8) == std::string("\x89PNG\r\n\x1a\n", 8);
}

struct ToolRun {
  int exit_code = -1;
  std::string out, err;
  double seconds = 0.0;
};

// Runs `exe args` through the shell, its stdout and stderr kept in files in `scratch`.
inline ToolRun run_tool(const std::string& exe, const std::string& args, const std::filesystem::path& scratch) {
  const std::string cmd =
      exe + " " + args + " >" + (scratch / "stdout").string() + " 2>" + (scratch / "stderr").string();
  const auto start = std::chrono::steady_clock::now();
  const int status = std::system(cmd.c_str());
  const std::chrono::duration<double> took = std::chrono::steady_clock::now() - start;
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, slurp(scratch / "stdout"), slurp(scratch / "stderr"),
          took.count()};
}

}  // namespace hystloop::test
