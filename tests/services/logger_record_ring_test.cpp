#include "record/record_ring.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <cstdint>
#include <cstring>
#include <random>
#include <thread>
#include <vector>

#include "core/errors.hpp"
#include "support/allocation_counter.hpp"

namespace hystloop {
namespace {

using Push = RecordRing::PushResult;

// A payload whose bytes are a function of (id, size), so a reader can check it.
std::vector<std::uint8_t> payload(std::uint64_t id, std::size_t size) {
  std::vector<std::uint8_t> bytes(size);
  for (std::size_t i = 0; i < size; ++i) bytes[i] = static_cast<std::uint8_t>((id * 131 + i * 7) & 0xFF);
  return bytes;
}

TEST(RecordRing, PassesRecordsThroughInOrder) {
  RecordRing ring(4096);
  for (std::uint32_t i = 0; i < 10; ++i) {
    const auto bytes = payload(i, 10 + i);
    ASSERT_EQ(ring.try_push(i % 3, 1000 + i, bytes.data(), bytes.size()), Push::kOk);
  }
  std::uint32_t seen = 0;
  const std::size_t n = ring.drain([&](const RecordRing::Record& r) {
    EXPECT_EQ(r.channel, seen % 3);
    EXPECT_EQ(r.recv_utime, 1000 + seen);
    const auto want = payload(seen, 10 + seen);
    ASSERT_EQ(r.size, want.size());
    EXPECT_EQ(std::memcmp(r.data, want.data(), want.size()), 0);
    ++seen;
  });
  EXPECT_EQ(n, 10u);
  EXPECT_TRUE(ring.empty());
}

TEST(RecordRing, FullRingRefusesAndRecoversAfterDrain) {
  RecordRing ring(4096);
  const auto bytes = payload(1, 40);  // 64 bytes a record with its header
  int pushed = 0;
  while (ring.try_push(0, 0, bytes.data(), bytes.size()) == Push::kOk) ++pushed;
  EXPECT_EQ(pushed, 4096 / 64);
  EXPECT_EQ(ring.try_push(0, 0, bytes.data(), bytes.size()), Push::kFull);
  EXPECT_EQ(ring.drain([](const RecordRing::Record&) {}, 1), 1u);
  EXPECT_EQ(ring.try_push(0, 0, bytes.data(), bytes.size()), Push::kOk);
}

TEST(RecordRing, RefusesARecordLargerThanAQuarter) {
  RecordRing ring(8192);
  std::vector<std::uint8_t> big(ring.max_payload_bytes() + 1);
  EXPECT_EQ(ring.try_push(0, 0, big.data(), big.size()), Push::kTooLarge);
  big.resize(ring.max_payload_bytes());
  EXPECT_EQ(ring.try_push(0, 0, big.data(), big.size()), Push::kOk);
}

TEST(RecordRing, RefusesABadCapacity) {
  EXPECT_THROW(RecordRing(100), ParameterError);
  try {
    RecordRing ring(10);
    ADD_FAILURE() << "RecordRing(10) did not throw";
  } catch (const ParameterError& e) {
    EXPECT_EQ(e.field(), "queue_bytes");
  }
}

TEST(RecordRing, WrapsWithoutSplittingAndPushAllocatesNothing) {
  RecordRing ring(4096);
  std::mt19937_64 rng(7);
  std::uint64_t next_id = 0, next_read = 0;
  std::vector<std::vector<std::uint8_t>> payloads;
  for (std::uint64_t id = 0; id < 5000; ++id) payloads.push_back(payload(id, rng() % 300));
  for (int round = 0; round < 2000 && next_read < payloads.size(); ++round) {
    const hystloop::testing::AllocationCounter allocations;
    while (next_id < payloads.size() && ring.try_push(static_cast<std::uint32_t>(next_id), 0, payloads[next_id].data(),
                                                      payloads[next_id].size()) == Push::kOk) {
      ++next_id;
    }
    EXPECT_EQ(allocations.allocations(), 0u);
    ring.drain(
        [&](const RecordRing::Record& r) {
          ASSERT_EQ(r.channel, static_cast<std::uint32_t>(next_read));
          ASSERT_EQ(r.size, payloads[next_read].size());
          ASSERT_TRUE(r.size == 0 || std::memcmp(r.data, payloads[next_read].data(), r.size) == 0);
          ++next_read;
        },
        1 + rng() % 20);
  }
  EXPECT_EQ(next_read, payloads.size());
}

// Two threads, as in the logger: everything pushed successfully arrives, once, in order,
// intact; what was refused is exactly what is missing. With `retry` the producer waits
// for room instead of dropping, and everything must arrive.
void run_two_threads(bool retry) {
#ifdef __SANITIZE_ADDRESS__
  constexpr std::uint64_t kRecords = 50000;
#else
  constexpr std::uint64_t kRecords = 400000;
#endif
  RecordRing ring(1 << 14);
  std::uint64_t refused = 0;
  std::atomic<bool> done{false};
  std::thread producer([&] {
    std::mt19937_64 rng(42);
    std::uint8_t bytes[200];
    for (std::uint64_t id = 0; id < kRecords; ++id) {
      const std::size_t size = 8 + rng() % 192;
      std::memcpy(bytes, &id, sizeof id);
      for (std::size_t i = 8; i < size; ++i) bytes[i] = static_cast<std::uint8_t>(id + i);
      while (ring.try_push(0, static_cast<std::int64_t>(id), bytes, size) != Push::kOk) {
        if (!retry) {
          ++refused;
          break;
        }
        std::this_thread::yield();
      }
    }
    done.store(true, std::memory_order_release);
  });
  std::uint64_t received = 0, last_id = 0, errors = 0;
  bool first = true;
  auto check = [&](const RecordRing::Record& r) {
    std::uint64_t id = 0;
    std::memcpy(&id, r.data, sizeof id);
    if (static_cast<std::int64_t>(id) != r.recv_utime || (!first && id <= last_id)) ++errors;
    for (std::size_t i = 8; i < r.size; ++i) errors += r.data[i] != static_cast<std::uint8_t>(id + i);
    first = false;
    last_id = id;
    ++received;
  };
  while (!done.load(std::memory_order_acquire)) {
    if (ring.drain(check) == 0) std::this_thread::yield();
  }
  producer.join();
  ring.drain(check);
  EXPECT_EQ(errors, 0u);
  EXPECT_EQ(received + refused, kRecords);
  EXPECT_GT(received, 0u);
  if (retry) {
    EXPECT_EQ(received, kRecords);
  }
}

TEST(RecordRing, ProducerAndConsumerThreadsLoseNothingUncounted) { run_two_threads(false); }
TEST(RecordRing, ProducerAndConsumerThreadsWithRetryLoseNothing) { run_two_threads(true); }

}  // namespace
}  // namespace hystloop
