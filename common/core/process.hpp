#pragma once
// Process set-up shared by every service main(): a clean stop on SIGINT/SIGTERM,
// and the optional real-time preparation (locked memory, SCHED_FIFO, CPU
// affinity) that is refused on an ordinary desktop without being fatal.
//
//   install_stop_handlers();
//   lock_memory(); set_realtime_priority(80); set_cpu_affinity({1});
//   while (!stop_requested()) { poll({lcm_fd, stop_fd()}, ...); ... }
//
// A second SIGINT/SIGTERM while a stop is already pending restores the default
// action and re-raises: a process stuck in its shutdown can still be killed
// from the terminal with a second Ctrl-C.

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace hystloop {

// Installs the SIGINT/SIGTERM handlers and creates the stop eventfd (idempotent).
// Throws std::system_error if the eventfd or sigaction fails.
void install_stop_handlers();
// True once SIGINT/SIGTERM arrived or request_stop() was called. Lock-free,
// async-signal-safe: may be read on the per-sample path.
bool stop_requested() noexcept;
// What the signal handler does, for a service that decides to stop itself.
void request_stop() noexcept;
// The signal that asked for the stop (SIGINT, SIGTERM), 0 for request_stop() or none.
int stop_signal() noexcept;
// An eventfd that becomes readable when a stop is requested, so a poll() loop
// (e.g. on LCM's file descriptor) wakes at once. -1 before install_stop_handlers().
int stop_fd() noexcept;
// Clears the request and drains the eventfd (tests; a service that re-arms).
void clear_stop_request() noexcept;

// Outcome of an optional set-up step: refused is not fatal, it is reported.
struct SetupStatus {
  bool ok = false;
  std::string detail;  // what was done, or why it was refused (errno text)
};

// mlockall(MCL_CURRENT | MCL_FUTURE): no page faults on the loop's memory later.
// Logs a warning through spdlog's default logger when refused.
SetupStatus lock_memory();
// SCHED_FIFO at `priority` (1..99) for the calling thread. Logs a warning when
// refused. Throws ParameterError("rt_priority") outside 1..99.
SetupStatus set_realtime_priority(int priority);
// Back to SCHED_OTHER for the calling thread (undoes set_realtime_priority).
SetupStatus set_normal_priority();
// Pins the calling thread to `cpus`. Logs a warning when refused. Throws
// ParameterError("cpus") for an empty list or an index outside 0..CPU_SETSIZE-1.
SetupStatus set_cpu_affinity(const std::vector<int>& cpus);
// CPUs the calling thread may run on.
std::vector<int> current_cpu_affinity();

// This process's resource use so far (getrusage(RUSAGE_SELF)), for status reports.
struct ResourceUsage {
  double user_cpu_s = 0;
  double system_cpu_s = 0;
  std::int64_t peak_rss_bytes = 0;
  std::int64_t minor_faults = 0;
  std::int64_t major_faults = 0;
  std::int64_t voluntary_switches = 0;    // the process slept (waited for I/O or a timer)
  std::int64_t involuntary_switches = 0;  // the scheduler took the CPU away
};
ResourceUsage read_resource_usage() noexcept;

// The host name (for HX_STATUS), "unknown" if it cannot be read.
std::string host_name();

// Runs `exe args...` with `dir` as its working directory, its standard output silenced and its
// standard error into `stderr_file` (relative to dir), and waits for it (the tools' gnuplot).
// Its exit status; -1 when it could not run or did not exit. What this process has buffered is
// flushed first: the child's freopen would write it a second time.
int run_program_in(const std::filesystem::path& dir, const std::filesystem::path& exe,
                   const std::vector<std::string>& args, const char* stderr_file = "/dev/null");

}  // namespace hystloop
