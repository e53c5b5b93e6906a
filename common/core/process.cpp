#include "core/process.hpp"

#include <pthread.h>
#include <sched.h>
#include <sys/eventfd.h>
#include <sys/mman.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <iostream>
#include <mutex>
#include <system_error>

#include <spdlog/spdlog.h>

#include "core/errors.hpp"

namespace hystloop {
namespace {

std::atomic<bool> g_stop{false};
std::atomic<int> g_stop_signal{0};
std::atomic<int> g_stop_fd{-1};
static_assert(std::atomic<bool>::is_always_lock_free && std::atomic<int>::is_always_lock_free,
              "the signal handler needs lock-free atomics");

void wake_stop_fd() noexcept {
  const int fd = g_stop_fd.load();
  if (fd >= 0) {
    const std::uint64_t one = 1;
    // A full counter (EAGAIN) still leaves the fd readable; nothing to do on error.
    [[maybe_unused]] const ssize_t n = ::write(fd, &one, sizeof one);
  }
}

extern "C" void on_stop_signal(int sig) {
  const int saved_errno = errno;  // write() below may change it under the interrupted code
  if (g_stop.exchange(true)) {
    std::signal(sig, SIG_DFL);  // second signal: the user insists
    std::raise(sig);
  } else {
    g_stop_signal.store(sig);
    wake_stop_fd();
  }
  errno = saved_errno;
}

SetupStatus refused(const std::string& what, int err) {
  SetupStatus s{false, what + " refused: " + std::strerror(err)};
  spdlog::warn("{} (continuing without it)", s.detail);
  return s;
}

double seconds(const timeval& tv) { return static_cast<double>(tv.tv_sec) + 1e-6 * static_cast<double>(tv.tv_usec); }

}  // namespace

void install_stop_handlers() {
  static std::once_flag once;
  std::call_once(once, [] {
    const int fd = ::eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
    if (fd < 0) throw std::system_error(errno, std::generic_category(), "eventfd");
    g_stop_fd.store(fd);
    struct sigaction sa {};
    sa.sa_handler = on_stop_signal;
    sigemptyset(&sa.sa_mask);
    sa.sa_flags = 0;  // no SA_RESTART: a blocking call returns EINTR and the loop looks
    for (const int sig : {SIGINT, SIGTERM}) {
      if (::sigaction(sig, &sa, nullptr) != 0) {
        throw std::system_error(errno, std::generic_category(), "sigaction");
      }
    }
  });
}

bool stop_requested() noexcept { return g_stop.load(std::memory_order_relaxed); }

void request_stop() noexcept {
  if (!g_stop.exchange(true)) wake_stop_fd();
}

int stop_signal() noexcept { return g_stop_signal.load(); }
int stop_fd() noexcept { return g_stop_fd.load(); }

void clear_stop_request() noexcept {
  g_stop.store(false);
  g_stop_signal.store(0);
  const int fd = g_stop_fd.load();
  if (fd >= 0) {
    std::uint64_t value = 0;
    [[maybe_unused]] const ssize_t n = ::read(fd, &value, sizeof value);  // EAGAIN when already empty
  }
}

SetupStatus lock_memory() {
  if (::mlockall(MCL_CURRENT | MCL_FUTURE) != 0) return refused("mlockall", errno);
  spdlog::info("memory locked (mlockall)");
  return {true, "memory locked (mlockall current and future)"};
}

SetupStatus set_realtime_priority(int priority) {
  require_in_range("rt_priority", priority, 1, 99);
  sched_param param{};
  param.sched_priority = priority;
  const int err = ::pthread_setschedparam(::pthread_self(), SCHED_FIFO, &param);
  if (err != 0) return refused("SCHED_FIFO priority " + std::to_string(priority), err);
  spdlog::info("running SCHED_FIFO at priority {}", priority);
  return {true, "SCHED_FIFO priority " + std::to_string(priority)};
}

SetupStatus set_normal_priority() {
  sched_param param{};
  param.sched_priority = 0;
  const int err = ::pthread_setschedparam(::pthread_self(), SCHED_OTHER, &param);
  if (err != 0) return refused("SCHED_OTHER", err);
  return {true, "SCHED_OTHER"};
}

SetupStatus set_cpu_affinity(const std::vector<int>& cpus) {
  if (cpus.empty()) throw ParameterError("cpus", "must name at least one CPU");
  cpu_set_t set;
  CPU_ZERO(&set);
  std::string list;
  for (const int cpu : cpus) {
    require_in_range("cpus", cpu, 0, CPU_SETSIZE - 1);
    CPU_SET(static_cast<std::size_t>(cpu), &set);
    if (!list.empty()) list += ',';
    list += std::to_string(cpu);
  }
  const int err = ::pthread_setaffinity_np(::pthread_self(), sizeof set, &set);
  if (err != 0) return refused("CPU affinity {" + list + "}", err);
  spdlog::info("pinned to CPU {}", list);
  return {true, "pinned to CPU " + list};
}

std::vector<int> current_cpu_affinity() {
  cpu_set_t set;
  CPU_ZERO(&set);
  std::vector<int> cpus;
  if (::pthread_getaffinity_np(::pthread_self(), sizeof set, &set) != 0) return cpus;
  for (int cpu = 0; cpu < CPU_SETSIZE; ++cpu) {
    if (CPU_ISSET(static_cast<std::size_t>(cpu), &set)) cpus.push_back(cpu);
  }
  return cpus;
}

ResourceUsage read_resource_usage() noexcept {
  rusage ru{};
  ResourceUsage out;
  if (::getrusage(RUSAGE_SELF, &ru) != 0) return out;
  out.user_cpu_s = seconds(ru.ru_utime);
  out.system_cpu_s = seconds(ru.ru_stime);
  out.peak_rss_bytes = static_cast<std::int64_t>(ru.ru_maxrss) * 1024;  // Linux: kilobytes
  out.minor_faults = ru.ru_minflt;
  out.major_faults = ru.ru_majflt;
  out.voluntary_switches = ru.ru_nvcsw;
  out.involuntary_switches = ru.ru_nivcsw;
  return out;
}

std::string host_name() {
  char buf[256] = {};
  if (::gethostname(buf, sizeof buf - 1) != 0) return "unknown";
  return buf;
}

int run_program_in(const std::filesystem::path& dir, const std::filesystem::path& exe,
                   const std::vector<std::string>& args, const char* stderr_file) {
  std::string program = exe.string();
  std::vector<std::string> copy = args;  // execv takes char*, not const char*
  std::vector<char*> argv{program.data()};
  for (auto& a : copy) argv.push_back(a.data());
  argv.push_back(nullptr);
  std::cout.flush();
  std::fflush(nullptr);
  const pid_t pid = ::fork();
  if (pid < 0) return -1;
  if (pid == 0) {
    if (::chdir(dir.c_str()) != 0) ::_exit(126);
    if (std::freopen("/dev/null", "w", stdout) == nullptr) ::_exit(126);
    if (std::freopen(stderr_file, "w", stderr) == nullptr) ::_exit(126);
    ::execv(program.c_str(), argv.data());
    ::_exit(127);
  }
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR) return -1;
  }
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

}  // namespace hystloop
