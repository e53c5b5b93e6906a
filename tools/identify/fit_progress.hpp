#pragma once
// Progress of a long fit on stderr: while a stage runs ("fitting mem on 2000000 samples"), a
// background thread prints "hystloop-identify: ... 12 s" every period, so a user of a 10 M-row
// record sees the tool is alive. The fitters stay free of clocks and output; this only
// watches the time from outside. Off unless asked for (--progress) or stderr is a terminal.

#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <mutex>
#include <string>
#include <thread>

namespace hystloop {

class FitProgress {
 public:
  // out == nullptr: silent (every call a no-op).
  FitProgress(std::FILE* out, std::chrono::milliseconds period);
  ~FitProgress();  // stops the thread
  FitProgress(const FitProgress&) = delete;
  FitProgress& operator=(const FitProgress&) = delete;

  // Starts reporting a new stage (its elapsed time counted from now); the first line comes one
  // period later, so short stages print nothing.
  void stage(std::string label);
  // Stops reporting until the next stage(); prints "<label>: done in N s" if a line was printed.
  void done();

 private:
  void run();

  std::FILE* out_;
  std::chrono::milliseconds period_;
  std::mutex mutex_;
  std::condition_variable wake_;
  std::string label_;
  std::chrono::steady_clock::time_point started_{};
  bool active_ = false;
  bool printed_ = false;
  bool stop_ = false;
  std::thread thread_;
};

// True for --progress, or when stderr is a terminal (isatty).
bool progress_wanted(bool flag) noexcept;

}  // namespace hystloop
