#include "fit_progress.hpp"

#include <unistd.h>

namespace hystloop {

FitProgress::FitProgress(std::FILE* out, std::chrono::milliseconds period) : out_(out), period_(period) {
  if (out_ != nullptr) thread_ = std::thread([this] { run(); });
}

FitProgress::~FitProgress() {
  {
    std::lock_guard lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();
}

void FitProgress::stage(std::string label) {
  if (out_ == nullptr) return;
  {
    std::lock_guard lock(mutex_);
    label_ = std::move(label);
    started_ = std::chrono::steady_clock::now();
    active_ = true;
    printed_ = false;
  }
  wake_.notify_all();
}

void FitProgress::done() {
  if (out_ == nullptr) return;
  std::lock_guard lock(mutex_);
  if (active_ && printed_) {
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - started_).count();
    std::fprintf(out_, "hystloop-identify: %s: done in %.1f s\n", label_.c_str(), s);
    std::fflush(out_);
  }
  active_ = false;
}

void FitProgress::run() {
  std::unique_lock lock(mutex_);
  while (!stop_) {
    if (!active_) {
      wake_.wait(lock, [this] { return stop_ || active_; });
      continue;
    }
    const auto since = started_;
    const auto next = std::chrono::steady_clock::now() + period_;
    // Wakes early only to stop or for a new stage.
    if (wake_.wait_until(lock, next, [&] { return stop_ || !active_ || started_ != since; })) continue;
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - started_).count();
    std::fprintf(out_, "hystloop-identify: %s: %.1f s\n", label_.c_str(), s);
    std::fflush(out_);
    printed_ = true;
  }
}

bool progress_wanted(bool flag) noexcept { return flag || ::isatty(STDERR_FILENO) == 1; }

}  // namespace hystloop
