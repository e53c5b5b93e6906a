#pragma once
// A typed LCM subscription that never lets a bad message through and never throws into
// LCM's C code. It subscribes with LCM's raw (undecoded) C handler -- lcm_subscribe, not
// the C++ wrapper, whose callback builds a std::string of the channel name per message
// (an allocation once prefix + name exceed 15 characters) -- then for each message:
//   fingerprint is T's            else kWrongType
//   length fields fit the buffer  else kDecodeFailed   (checked before decode allocates)
//   on a keyed rig's authenticated channel (lcm/rig_auth.hpp), the trailer after the encoding
//   verifies                      else kUnsigned / kBadMac / kReplayed / kSkewed
//                                 (any other trailing bytes: kSizeMismatch)
//   otherwise nothing follows the encoding but perhaps a trailer, ignored  else kSizeMismatch
//   decode succeeds               else kDecodeFailed
//   decoded size == encoding size else kSizeMismatch
//   value check passes            else kNonFinite / kOutOfRange
//   handler returns normally      else kHandlerFailed
// and counts each outcome. Decoding goes into a message allocated at construction; the
// accepted one is swapped into latest(), so a rejected buffer never overwrites it.
// Receiving a fixed-size type allocates nothing.
//
// Threading: LCM dispatches in whichever thread calls handle*, so the handler and
// counters belong to that thread. The lcm::LCM must outlive the Subscription.

#include <climits>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>

#include <lcm/lcm-cpp.hpp>

#include "lcm/message_checks.hpp"
#include "lcm/message_storage.hpp"
#include "auth/message_auth.hpp"
#include "core/clock.hpp"
#include "lcm/reject_reason.hpp"
#include "lcm/rig_auth.hpp"
#include "lcm/wire_layout.hpp"

namespace hystloop {

template <class T>
class Subscription {
 public:
  // Called with each accepted message and its receive time [us since the epoch].
  using Handler = std::function<void(const T& msg, std::int64_t recv_utime)>;
  // Told about each rejection (e.g. to log the first one); must not throw.
  using RejectHandler = std::function<void(RejectReason reason)>;

  struct Options {
    // Messages LCM queues for this subscription before dropping (0 = LCM's default, 30).
    // A 10 kHz channel read every millisecond needs more than the default.
    int queue_capacity = 0;
    MessageCheck<T> check = default_message_check<T>();  // nullptr = accept any decodable message
    RejectHandler on_reject;
    // The rig's key and skew; nullptr = keyless (trailers ignored). Used only on an
    // authenticated channel (is_authenticated_channel).
    std::shared_ptr<const RigAuth> auth = process_rig_auth();
  };

  Subscription(lcm::LCM& lcm, std::string channel, Handler handler = {}, Options options = {})
      : lcm_(lcm), channel_(std::move(channel)), handler_(std::move(handler)), options_(std::move(options)) {
    reserve_storage(scratch_);
    reserve_storage(latest_);
    subscription_ = lcm_subscribe(lcm_.getUnderlyingLCM(), channel_.c_str(), &Subscription::on_raw, this);
    if (subscription_ == nullptr) throw std::runtime_error("LCM could not subscribe to " + channel_);
    if (options_.queue_capacity > 0) lcm_subscription_set_queue_capacity(subscription_, options_.queue_capacity);
    if (options_.auth != nullptr && is_authenticated_channel(channel_)) {
      // Nothing signed before this receiver existed is taken (auth/message_auth.hpp: replay).
      verifier_.emplace(options_.auth->key, options_.auth->max_skew_us, wall_utime());
    }
  }

  ~Subscription() { lcm_unsubscribe(lcm_.getUnderlyingLCM(), subscription_); }
  Subscription(const Subscription&) = delete;
  Subscription& operator=(const Subscription&) = delete;

  // Processes one encoded message exactly as if LCM had delivered it (LCM calls this;
  // tests call it to inject corrupted bytes).
  void receive(const void* data, std::size_t size, std::int64_t recv_utime) noexcept {
    ++counters_.received;
    if (size < 8 || size > static_cast<std::size_t>(INT_MAX)) return reject(RejectReason::kDecodeFailed);
    if (wire_fingerprint(data, size) != T::getHash()) return reject(RejectReason::kWrongType);
    const std::int64_t walked = walk_wire_layout(wire_layout_of<T>(), data, size);
    if (walked < 0) return reject(RejectReason::kDecodeFailed);
    const auto body_size = static_cast<std::size_t>(walked);
    const auto* bytes = static_cast<const unsigned char*>(data);
    if (verifier_) {
      switch (verifier_->verify(channel_, bytes, body_size, bytes + body_size, size - body_size, recv_utime)) {
        case AuthResult::kOk: break;
        case AuthResult::kUnsigned: return reject(RejectReason::kUnsigned);
        case AuthResult::kMalformed: return reject(RejectReason::kSizeMismatch);
        case AuthResult::kBadMac: return reject(RejectReason::kBadMac);
        case AuthResult::kReplayed: return reject(RejectReason::kReplayed);
        case AuthResult::kSkewed: return reject(RejectReason::kSkewed);
      }
    } else if (body_size != size && !has_auth_magic(bytes + body_size, size - body_size)) {
      return reject(RejectReason::kSizeMismatch);
    }

    int decoded = -1;
    clear_arrays(scratch_);
    try {
      decoded = scratch_.decode(data, 0, static_cast<int>(body_size));
    } catch (...) {  // a string longer than any reserve could throw bad_alloc
      decoded = -1;
    }
    if (decoded < 0) return reject(RejectReason::kDecodeFailed);
    if (static_cast<std::size_t>(decoded) != body_size) return reject(RejectReason::kSizeMismatch);

    if (options_.check != nullptr) {
      switch (options_.check(scratch_)) {
        case Verdict::kOk: break;
        case Verdict::kNonFinite: return reject(RejectReason::kNonFinite);
        case Verdict::kOutOfRange: return reject(RejectReason::kOutOfRange);
      }
    }
    std::swap(latest_, scratch_);
    ++valid_;
    if (handler_) {
      try {
        handler_(latest_, recv_utime);
      } catch (...) {
        return reject(RejectReason::kHandlerFailed);
      }
    }
    ++counters_.accepted;
  }

  // The last message that passed every check (value-initialised until one has).
  const T& latest() const noexcept { return latest_; }
  // Messages that passed every check, whether or not the handler then threw.
  std::uint64_t valid_count() const noexcept { return valid_; }
  const EndpointCounters& counters() const noexcept { return counters_; }
  const std::string& channel() const noexcept { return channel_; }
  // True when messages must carry a valid signature (a keyed rig, an authenticated channel).
  bool authenticated() const noexcept { return verifier_.has_value(); }

 private:
  static void on_raw(const lcm_recv_buf_t* rbuf, const char* /*channel*/, void* self) noexcept {
    static_cast<Subscription*>(self)->receive(rbuf->data, rbuf->data_size, rbuf->recv_utime);
  }

  void reject(RejectReason reason) noexcept {
    counters_.count(reason);
    if (options_.on_reject) {
      try {
        options_.on_reject(reason);
      } catch (...) {  // a reporting failure must not reach LCM either
      }
    }
  }

  lcm::LCM& lcm_;
  std::string channel_;
  Handler handler_;
  Options options_;
  lcm_subscription_t* subscription_ = nullptr;
  T scratch_{};
  T latest_{};
  std::uint64_t valid_ = 0;
  EndpointCounters counters_;
  std::optional<MessageVerifier> verifier_;
};

}  // namespace hystloop
