// libFuzzer target: every message type through the receive path a Subscription runs — the
// length fields walked before decoding (common/lcm/wire_layout.hpp), lcm-gen's decode into a
// reused, reserved message, the decoded size against the walked size, the value contract
// (common/lcm/message_checks.hpp) — then a re-encode of what was accepted, which must decode
// back to the same size. What follows the walked encoding goes through a keyed rig's check
// (common/auth/message_auth.hpp): no input can carry a trailer the verifier takes, since the
// fuzzer does not know the key; one that did would be a hole in the MAC check or its framing.
// The same holds for the logger's check of the whole message (record/record_auth.hpp).
// A MEM parameter set the contract accepts then meets the receivers' plausibility check
// (common/models/gain_plausibility.hpp): refused with a ParameterError, or let through only with
// a finite small-signal gain inside the band: nothing else may escape it.
// The first input byte picks the type; the rest follows its fingerprint.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <type_traits>
#include <vector>

#include "auth/message_auth.hpp"
#include "core/errors.hpp"
#include "lcm/message_checks.hpp"
#include "lcm/message_storage.hpp"
#include "lcm/wire_layout.hpp"
#include "models/gain_plausibility.hpp"
#include "models/model_set.hpp"
#include "record/record_auth.hpp"

namespace {

using namespace hystloop;

// A keyed receiver: a key the fuzzer never sees, every counter since the epoch within the skew.
MessageVerifier& verifier() {
  static MessageVerifier v = [] {
    RigKey key;
    for (std::size_t i = 0; i < key.bytes.size(); ++i) key.bytes[i] = static_cast<unsigned char>(0xA5 ^ (13 * i));
    return MessageVerifier(key, INT64_MAX / 4, 1);
  }();
  return v;
}

// What the compensator and the re-identifier ask of a set whose values passed the contract.
void check_plausibility(const mem_params_t& msg) {
  ModelParamSet set;
  set.kind = ModelKind::mem;
  set.mem = MemParams{msg.c1, msg.c2, msg.c3};
  const GainPlausibility rig{};
  try {
    require_plausible(set, rig);
  } catch (const ParameterError&) {
    return;  // refused, naming the field: what a receiver counts
  }
  const GainRange g = small_signal_gain(set, rig);
  if (!(g.min_m_per_V >= rig.min_gain_m_per_V() && g.max_m_per_V <= rig.max_gain_m_per_V())) std::abort();
}

template <class T>
void receive(const std::uint8_t* data, std::size_t size) {
  std::vector<std::uint8_t> buffer(8 + size);
  const std::int64_t hash = T::getHash();
  for (int i = 0; i < 8; ++i)
    buffer[static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(static_cast<std::uint64_t>(hash) >> (56 - 8 * i));
  if (size > 0) std::memcpy(buffer.data() + 8, data, size);

  const std::int64_t walked = walk_wire_layout(wire_layout_of<T>(), buffer.data(), buffer.size());
  if (walked < 0) return;  // refused before decoding: what a Subscription counts as decode_failed
  const auto body = static_cast<std::size_t>(walked);
  if (body < buffer.size() && verifier().verify("HX_SENSOR", buffer.data(), body, buffer.data() + body,
                                                buffer.size() - body, 1'800'000'000'000'000) == AuthResult::kOk) {
    std::abort();
  }
  // The logger's and the log readers' check (record/record_auth.hpp), which takes the trailer
  // from the end of the message whatever its layout: nothing it can be given verifies either.
  if (verify_recorded(verifier(), "HX_COMMAND", buffer.data(), buffer.size(), 1'800'000'000'000'000) ==
      AuthResult::kOk) {
    std::abort();
  }
  static T msg = [] {
    T m{};
    reserve_storage(m);
    return m;
  }();
  clear_arrays(msg);
  const int decoded = msg.decode(buffer.data(), 0, static_cast<int>(buffer.size()));
  if (decoded < 0) return;
  // The walk said how long the message is; decode must agree, or the walk lets something through.
  if (decoded != walked) std::abort();
  if (check_message(msg) != Verdict::kOk || !arrays_consistent(msg)) return;
  if constexpr (std::is_same_v<T, mem_params_t>) check_plausibility(msg);
  // Accepted: what a service would publish again must encode and decode to the same length.
  std::vector<std::uint8_t> again(static_cast<std::size_t>(msg.getEncodedSize()));
  if (msg.encode(again.data(), 0, static_cast<int>(again.size())) != static_cast<int>(again.size())) std::abort();
  T back{};
  if (back.decode(again.data(), 0, static_cast<int>(again.size())) != static_cast<int>(again.size())) std::abort();
  if (check_message(back) != Verdict::kOk) std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  const std::uint8_t* body = data + 1;
  const std::size_t n = size - 1;
  switch (data[0] % 9) {
    case 0: receive<sensor_block_t>(body, n); break;
    case 1: receive<command_block_t>(body, n); break;
    case 2: receive<trajectory_t>(body, n); break;
    case 3: receive<mem_params_t>(body, n); break;
    case 4: receive<service_status_t>(body, n); break;
    case 5: receive<control_t>(body, n); break;
    case 6: receive<model_params_t>(body, n); break;
    case 7: receive<sim_truth_t>(body, n); break;
    default: receive<scan_t>(body, n); break;
  }
  return 0;
}
