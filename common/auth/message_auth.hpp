#pragma once
// The authentication trailer of a signed LCM message, its signer and its verifier.
//
// A signed message is the ordinary LCM encoding followed by a fixed 52-byte trailer:
//   "HXA1" | sender id (8 bytes, big-endian) | counter (8 bytes, big-endian) | MAC (32 bytes)
// MAC = HMAC-SHA-512-256 (libsodium crypto_auth) with the rig key over
//   channel length (4 bytes, big-endian) | channel name | LCM bytes | "HXA1" | sender id | counter
// so a message cannot be altered, moved to another channel, or given another sender or counter.
// LCM decoders read what the type needs and ignore the bytes after it, so lcm-spy and
// lcm-logger see an ordinary message.
//
// Replay: each signer draws a random sender id when it is made, and its counter is its wall
// clock [us since the epoch], strictly increasing (max(last + 1, now)). A verifier keeps the
// last counter of each sender and refuses a counter <= it; a counter further than max_skew from
// the verifier's own wall clock is refused too, so a message recorded from a process that has
// since stopped (a sender the verifier never saw or has forgotten) is refused as well. A
// verifier also refuses every counter below the wall-clock time it was made (not_before): a
// receiver that has just started remembers no sender, and without that bound a message captured
// up to max_skew before it started (an ARM before the operator's DISARM, say) would pass once.
// The hosts of a rig therefore need synchronised clocks (chrony or PTP), to well within max_skew.
//
// Time is an argument (now_us); nothing here allocates or throws after construction.

#include <array>
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "auth/rig_key.hpp"

namespace hystloop {

inline constexpr std::array<unsigned char, 4> kAuthMagic{'H', 'X', 'A', '1'};
inline constexpr std::size_t kAuthMacBytes = 32;
inline constexpr std::size_t kAuthTrailerBytes = 4 + 8 + 8 + kAuthMacBytes;  // 52

// True if the last kAuthTrailerBytes of data[0..size) start with the magic. A receiver decides
// where the LCM encoding ends from the type's layout; this only checks what follows it.
bool has_auth_magic(const unsigned char* trailer, std::size_t trailer_size) noexcept;

class MessageSigner {
 public:
  // `sender_id` 0 draws a random non-zero one.
  explicit MessageSigner(const RigKey& key, std::uint64_t sender_id = 0);
  ~MessageSigner();
  MessageSigner(const MessageSigner&) = delete;
  MessageSigner& operator=(const MessageSigner&) = delete;

  // Writes the trailer of `body` (size bytes of LCM encoding) sent on `channel` at wall-clock
  // `now_us` to trailer[0..kAuthTrailerBytes).
  void sign(std::string_view channel, const unsigned char* body, std::size_t size, std::int64_t now_us,
            unsigned char* trailer) noexcept;

  std::uint64_t sender_id() const noexcept { return sender_id_; }
  std::int64_t last_counter() const noexcept { return last_counter_; }

 private:
  RigKey key_;
  std::uint64_t sender_id_;
  std::int64_t last_counter_ = 0;
};

enum class AuthResult : std::uint8_t {
  kOk,
  kUnsigned,   // no trailer
  kMalformed,  // trailing bytes that are not a trailer (wrong size or magic)
  kBadMac,     // altered, another channel, or another key
  kReplayed,   // counter not above the last one accepted from this sender, or below not_before
  kSkewed,     // counter further than max_skew from the receiver's clock (too old, or from the future)
};
std::string_view to_string(AuthResult result) noexcept;

class MessageVerifier {
 public:
  // Senders remembered at once; when more appear, the one heard from longest ago is forgotten
  // (its old messages are still refused once they are max_skew old).
  static constexpr std::size_t kMaxSenders = 32;

  // max_skew_us > 0; not_before_us: counters below it are refused as replayed (the receiver's
  // start, wall clock [us since the epoch]; 0 = no such bound).
  MessageVerifier(const RigKey& key, std::int64_t max_skew_us, std::int64_t not_before_us = 0);
  ~MessageVerifier();
  MessageVerifier(const MessageVerifier&) = delete;
  MessageVerifier& operator=(const MessageVerifier&) = delete;

  // Checks the trailer[0..trailer_size) that followed `body` on `channel`, received at
  // wall-clock `now_us`; records the counter when the result is kOk.
  AuthResult verify(std::string_view channel, const unsigned char* body, std::size_t body_size,
                    const unsigned char* trailer, std::size_t trailer_size, std::int64_t now_us) noexcept;

  std::int64_t max_skew_us() const noexcept { return max_skew_us_; }
  std::int64_t not_before_us() const noexcept { return not_before_us_; }
  // Senders forgotten to make room for a new one.
  std::uint64_t evictions() const noexcept { return evictions_; }

 private:
  struct Sender {
    std::uint64_t id = 0;  // 0 = free
    std::int64_t last_counter = 0;
  };

  RigKey key_;
  std::int64_t max_skew_us_;
  std::int64_t not_before_us_;
  std::array<Sender, kMaxSenders> senders_{};
  std::uint64_t evictions_ = 0;
};

}  // namespace hystloop
