#include "auth/message_auth.hpp"

#include <algorithm>
#include <cstring>
#include <stdexcept>

#include <sodium.h>

#include "auth/sodium_init.hpp"

namespace hystloop {
namespace {

static_assert(kAuthMacBytes == crypto_auth_hmacsha512256_BYTES);
static_assert(kRigKeyBytes == crypto_auth_hmacsha512256_KEYBYTES);

constexpr std::size_t kIdOffset = 4;
constexpr std::size_t kCounterOffset = 12;
constexpr std::size_t kMacOffset = 20;

void put_be64(unsigned char* out, std::uint64_t v) noexcept {
  for (int i = 7; i >= 0; --i) {
    out[i] = static_cast<unsigned char>(v & 0xFF);
    v >>= 8;
  }
}

std::uint64_t get_be64(const unsigned char* in) noexcept {
  std::uint64_t v = 0;
  for (int i = 0; i < 8; ++i) v = (v << 8) | in[i];
  return v;
}

// MAC over channel length | channel | body | trailer[0..kMacOffset).
void compute_mac(const RigKey& key, std::string_view channel, const unsigned char* body, std::size_t size,
                 const unsigned char* trailer_head, unsigned char* mac) noexcept {
  crypto_auth_hmacsha512256_state state;
  crypto_auth_hmacsha512256_init(&state, key.bytes.data(), key.bytes.size());
  unsigned char length[4];
  const auto n = static_cast<std::uint32_t>(channel.size());
  length[0] = static_cast<unsigned char>(n >> 24);
  length[1] = static_cast<unsigned char>(n >> 16);
  length[2] = static_cast<unsigned char>(n >> 8);
  length[3] = static_cast<unsigned char>(n);
  crypto_auth_hmacsha512256_update(&state, length, sizeof length);
  crypto_auth_hmacsha512256_update(&state, reinterpret_cast<const unsigned char*>(channel.data()), channel.size());
  crypto_auth_hmacsha512256_update(&state, body, size);
  crypto_auth_hmacsha512256_update(&state, trailer_head, kMacOffset);
  crypto_auth_hmacsha512256_final(&state, mac);
  sodium_memzero(&state, sizeof state);
}

}  // namespace

bool has_auth_magic(const unsigned char* trailer, std::size_t trailer_size) noexcept {
  return trailer != nullptr && trailer_size == kAuthTrailerBytes &&
         std::memcmp(trailer, kAuthMagic.data(), kAuthMagic.size()) == 0;
}

MessageSigner::MessageSigner(const RigKey& key, std::uint64_t sender_id) : key_(key), sender_id_(sender_id) {
  ensure_sodium();
  while (sender_id_ == 0) randombytes_buf(&sender_id_, sizeof sender_id_);
}

MessageSigner::~MessageSigner() { sodium_memzero(key_.bytes.data(), key_.bytes.size()); }

void MessageSigner::sign(std::string_view channel, const unsigned char* body, std::size_t size, std::int64_t now_us,
                         unsigned char* trailer) noexcept {
  last_counter_ = std::max(last_counter_ + 1, now_us);
  std::memcpy(trailer, kAuthMagic.data(), kAuthMagic.size());
  put_be64(trailer + kIdOffset, sender_id_);
  put_be64(trailer + kCounterOffset, static_cast<std::uint64_t>(last_counter_));
  compute_mac(key_, channel, body, size, trailer, trailer + kMacOffset);
}

std::string_view to_string(AuthResult result) noexcept {
  switch (result) {
    case AuthResult::kOk: return "ok";
    case AuthResult::kUnsigned: return "unsigned";
    case AuthResult::kMalformed: return "malformed";
    case AuthResult::kBadMac: return "bad_mac";
    case AuthResult::kReplayed: return "replayed";
    case AuthResult::kSkewed: return "skewed";
  }
  return "unknown";
}

MessageVerifier::MessageVerifier(const RigKey& key, std::int64_t max_skew_us, std::int64_t not_before_us)
    : key_(key), max_skew_us_(max_skew_us), not_before_us_(not_before_us) {
  ensure_sodium();
  if (max_skew_us <= 0) throw std::invalid_argument("MessageVerifier: max_skew_us must be > 0");
}

MessageVerifier::~MessageVerifier() { sodium_memzero(key_.bytes.data(), key_.bytes.size()); }

AuthResult MessageVerifier::verify(std::string_view channel, const unsigned char* body, std::size_t body_size,
                                   const unsigned char* trailer, std::size_t trailer_size,
                                   std::int64_t now_us) noexcept {
  if (trailer_size == 0) return AuthResult::kUnsigned;
  if (!has_auth_magic(trailer, trailer_size)) return AuthResult::kMalformed;
  unsigned char mac[kAuthMacBytes];
  compute_mac(key_, channel, body, body_size, trailer, mac);
  if (crypto_verify_32(mac, trailer + kMacOffset) != 0) return AuthResult::kBadMac;

  // Authentic from here on: the sender and counter are the signer's.
  const std::uint64_t id = get_be64(trailer + kIdOffset);
  const std::uint64_t raw_counter = get_be64(trailer + kCounterOffset);
  if (raw_counter > static_cast<std::uint64_t>(INT64_MAX)) return AuthResult::kSkewed;
  const auto counter = static_cast<std::int64_t>(raw_counter);
  // |counter - now| > max_skew, without overflow (both are >= 0 on any sane clock).
  if (counter < now_us - max_skew_us_ || counter - max_skew_us_ > now_us) return AuthResult::kSkewed;
  if (counter < not_before_us_) return AuthResult::kReplayed;

  Sender* slot = nullptr;
  Sender* oldest = &senders_[0];
  for (Sender& s : senders_) {
    if (s.id == id) {
      slot = &s;
      break;
    }
    if (s.id == 0 || (oldest->id != 0 && s.last_counter < oldest->last_counter)) oldest = &s;
  }
  if (slot != nullptr) {
    if (counter <= slot->last_counter) return AuthResult::kReplayed;
  } else {
    slot = oldest;
    if (slot->id != 0) ++evictions_;
    slot->id = id;
  }
  slot->last_counter = counter;
  return AuthResult::kOk;
}

}  // namespace hystloop
