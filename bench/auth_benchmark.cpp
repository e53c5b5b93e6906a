// The cost of the authenticated rig per message (README "Authenticated rig"): the trailer's
// HMAC-SHA-512-256 signed and checked for a 20-tick command block (one per sensor block), a 20-tick
// sensor block (500 a second at the former default bridge.block_ticks; 200 of 50 ticks now) and a
// MEM parameter set, beside the LCM encode they follow. Time per message; the
// verifier's figure includes its replay table.
#include <benchmark/benchmark.h>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "auth/message_auth.hpp"
#include "core/clock.hpp"
#include "hystloop/command_block_t.hpp"
#include "hystloop/mem_params_t.hpp"
#include "hystloop/sensor_block_t.hpp"
#include "lcm/blocks.hpp"
#include "lcm/message_storage.hpp"

namespace hystloop {
namespace {

RigKey bench_key() {
  RigKey k;
  for (std::size_t i = 0; i < k.bytes.size(); ++i) k.bytes[i] = static_cast<unsigned char>(3 * i + 1);
  return k;
}

std::vector<unsigned char> encoded_command_block() {
  command_block_t b{};
  reserve_storage(b);
  begin_block(b, 1000, wall_utime(), 999);
  for (std::int64_t t = 1000; t < 1020; ++t) append_tick(b, CommandTick{t, 12.5, 1e-6, 3, command_block_t::MODE_MEM});
  std::vector<unsigned char> bytes(static_cast<std::size_t>(b.getEncodedSize()) + kAuthTrailerBytes);
  b.encode(bytes.data(), 0, b.getEncodedSize());
  bytes.resize(static_cast<std::size_t>(b.getEncodedSize()));
  return bytes;
}

std::vector<unsigned char> encoded_params() {
  mem_params_t p{};
  p.utime = wall_utime();
  p.version = 12;
  p.publisher_id = 7;
  p.c1 = 5e-9;
  p.c2 = 1.5e-12;
  p.c3 = 1.1;
  p.residual_m = 1e-9;
  p.samples_used = 100000;
  p.window_s = 10;
  p.valid = true;
  p.source = "reident@stage-pc";
  std::vector<unsigned char> bytes(static_cast<std::size_t>(p.getEncodedSize()));
  p.encode(bytes.data(), 0, p.getEncodedSize());
  return bytes;
}

std::vector<unsigned char> encoded_sensor_block() {
  sensor_block_t b{};
  reserve_storage(b);
  begin_block(b, 1000, wall_utime(), 1e-4);
  for (std::int64_t t = 1000; t < 1020; ++t) {
    append_tick(b, SensorTick{wall_utime(), t, 12.5, 12.0, 0.5, 1e-6, 1.01e-6, 0});
  }
  std::vector<unsigned char> bytes(static_cast<std::size_t>(b.getEncodedSize()));
  b.encode(bytes.data(), 0, b.getEncodedSize());
  return bytes;
}

std::vector<unsigned char> message(int which) {
  switch (which) {
    case 0: return encoded_command_block();
    case 1: return encoded_params();
    default: return encoded_sensor_block();
  }
}
const char* label(int which) {
  switch (which) {
    case 0: return "command_block_t, 20 ticks";
    case 1: return "mem_params_t";
    default: return "sensor_block_t, 20 ticks";
  }
}

void BM_Sign(benchmark::State& state) {
  const int which = static_cast<int>(state.range(0));
  std::vector<unsigned char> bytes = message(which);
  const std::size_t body = bytes.size();
  bytes.resize(body + kAuthTrailerBytes);
  MessageSigner signer(bench_key());
  std::int64_t now = wall_utime();
  for (auto _ : state) {
    signer.sign("HX_COMMAND", bytes.data(), body, ++now, bytes.data() + body);
    benchmark::DoNotOptimize(bytes.data());
  }
  state.SetLabel(std::string(label(which)) + ", " + std::to_string(body) + " B");
}

void BM_Verify(benchmark::State& state) {
  const int which = static_cast<int>(state.range(0));
  std::vector<unsigned char> bytes = message(which);
  const std::size_t body = bytes.size();
  // Pre-signed trailers with increasing counters, so every check is a fresh, valid message.
  constexpr std::size_t kBatch = 1 << 14;
  std::vector<unsigned char> trailers(kBatch * kAuthTrailerBytes);
  MessageSigner signer(bench_key());
  const std::int64_t start = wall_utime();
  for (std::size_t i = 0; i < kBatch; ++i) {
    signer.sign("HX_COMMAND", bytes.data(), body, start + static_cast<std::int64_t>(i),
                &trailers[i * kAuthTrailerBytes]);
  }
  auto verifier = std::make_unique<MessageVerifier>(bench_key(), 3'600'000'000);
  std::size_t i = 0;
  std::int64_t refused = 0;
  for (auto _ : state) {
    if (i == kBatch) {
      state.PauseTiming();
      verifier = std::make_unique<MessageVerifier>(bench_key(), 3'600'000'000);
      i = 0;
      state.ResumeTiming();
    }
    refused += verifier->verify("HX_COMMAND", bytes.data(), body, &trailers[i * kAuthTrailerBytes], kAuthTrailerBytes,
                                start) != AuthResult::kOk;
    ++i;
  }
  if (refused != 0) state.SkipWithError("a valid message was refused");
  state.SetLabel(std::string(label(which)) + ", " + std::to_string(body) + " B");
}

void BM_Encode(benchmark::State& state) {  // what the trailer is added to, for scale
  command_block_t b{};
  reserve_storage(b);
  begin_block(b, 1000, wall_utime(), 999);
  for (std::int64_t t = 1000; t < 1020; ++t) append_tick(b, CommandTick{t, 12.5, 1e-6, 3, command_block_t::MODE_MEM});
  std::vector<unsigned char> bytes(static_cast<std::size_t>(b.getEncodedSize()));
  for (auto _ : state) {
    benchmark::DoNotOptimize(b.encode(bytes.data(), 0, static_cast<int>(bytes.size())));
  }
  state.SetLabel("command_block_t, 20 ticks");
}

BENCHMARK(BM_Sign)->Arg(0)->Arg(1)->Arg(2);
BENCHMARK(BM_Verify)->Arg(0)->Arg(1)->Arg(2);
BENCHMARK(BM_Encode);

}  // namespace
}  // namespace hystloop
