#pragma once
// Single-producer single-consumer ring of fixed capacity: the non-blocking handoff
// between a service's I/O thread and its real-time thread. try_push/try_pop never
// block, never allocate and never lock; a full queue refuses (the caller counts it).

#include <array>
#include <atomic>
#include <cstddef>
#include <optional>

namespace hystloop {

template <class T, std::size_t Capacity>
class SpscQueue {
  static_assert(Capacity >= 2 && (Capacity & (Capacity - 1)) == 0, "Capacity must be a power of two");

 public:
  bool try_push(const T& value) noexcept {
    const std::size_t head = head_.load(std::memory_order_relaxed);
    const std::size_t tail = tail_.load(std::memory_order_acquire);
    if (head - tail == Capacity) return false;
    slots_[head & (Capacity - 1)] = value;
    head_.store(head + 1, std::memory_order_release);
    return true;
  }

  std::optional<T> try_pop() noexcept {
    const std::size_t tail = tail_.load(std::memory_order_relaxed);
    const std::size_t head = head_.load(std::memory_order_acquire);
    if (head == tail) return std::nullopt;
    T value = slots_[tail & (Capacity - 1)];
    tail_.store(tail + 1, std::memory_order_release);
    return value;
  }

  std::size_t size() const noexcept {
    return head_.load(std::memory_order_acquire) - tail_.load(std::memory_order_acquire);
  }

 private:
  alignas(64) std::atomic<std::size_t> head_{0};
  alignas(64) std::atomic<std::size_t> tail_{0};
  std::array<T, Capacity> slots_{};
};

// Latest-value mailbox for one writer and one reader (parameters, trajectories): a
// triple buffer. The writer never blocks and the newest post always wins; the reader
// takes each new value at most once. No locks, no allocation.
template <class T>
class Mailbox {
 public:
  // Writer side.
  void post(const T& value) noexcept {
    slots_[back_] = value;
    // Publish the back slot as the middle one, marking it fresh; take the old middle.
    const unsigned old = middle_.exchange(back_ | kFresh, std::memory_order_acq_rel);
    back_ = old & kIndex;
  }

  // Reader side: the newest posted value, or nothing if none since the last take.
  std::optional<T> take() noexcept {
    if ((middle_.load(std::memory_order_acquire) & kFresh) == 0) return std::nullopt;
    const unsigned old = middle_.exchange(front_, std::memory_order_acq_rel);
    front_ = old & kIndex;
    return slots_[front_];
  }

 private:
  static constexpr unsigned kIndex = 3u;
  static constexpr unsigned kFresh = 4u;
  std::array<T, 3> slots_{};
  unsigned back_ = 0;  // writer's
  alignas(64) std::atomic<unsigned> middle_{1};
  alignas(64) unsigned front_ = 2;  // reader's
};

}  // namespace hystloop
