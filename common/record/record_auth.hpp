#pragma once
// What the record of a keyed rig holds, and how the logger and the log readers check it.
//
// On a keyed rig every service refuses a message on an authenticated channel (lcm/rig_auth.hpp)
// whose signature does not verify. The record holds what the rig could act on, so the logger
// verifies the same way and does not record what fails (it counts it by channel and reason),
// and a reader given the key verifies again and leaves out what fails: a log recorded by a
// keyless logger, or altered after it was written, then reads as what the rig accepted.
//
// The signature is checked over the message's bytes up to its last kAuthTrailerBytes (the
// trailer, auth/message_auth.hpp): the record keeps bytes of any type, so it does not walk the
// type's layout as a Subscription does; a message of a foreign layout that verifies was signed
// with the rig key, and the services' own checks refuse it as they would have live.
//
// A keyed logger writes a marker event first in each file of its recording, on
// <prefix>RECORD (kRecordSuffix): a service_status_t from process "logger" whose counter
// "keyed" is 1. A reader without the key that meets it warns that it did not verify.

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "auth/message_auth.hpp"
#include "lcm/rig_auth.hpp"

namespace hystloop {

inline constexpr std::string_view kRecordSuffix = "RECORD";
// AuthResult's values, kOk included (an index for counters by reason).
inline constexpr std::size_t kAuthResults = static_cast<std::size_t>(AuthResult::kSkewed) + 1;

// The result of verifying a recorded or received message of `size` bytes on `channel`: its
// trailer, if any, is its last kAuthTrailerBytes. `now_us` is its receive time [us].
AuthResult verify_recorded(MessageVerifier& verifier, std::string_view channel, const void* data, std::size_t size,
                           std::int64_t now_us) noexcept;

// The marker's encoding (a service_status_t, see above) for a recording started at `utime`.
std::vector<std::uint8_t> keyed_record_marker(std::int64_t utime);
// True if `channel` is <prefix>RECORD and data[0..size) is a marker saying the log is keyed.
bool is_keyed_record_marker(std::string_view channel, const void* data, std::size_t size) noexcept;

// A log reader's check of what it reads, in the order it was recorded (across the files of one
// recording): with the rig's key (auth non-null), an event on an authenticated channel of a file
// that starts with the keyed marker whose signature fails is left out and counted; without, or in
// a file recorded without a key (no marker: no signatures to check), nothing is left out, and the
// notes say which. Allocates (readers only; the logger keeps its own fixed counters).
class RecordCheck {
 public:
  explicit RecordCheck(std::shared_ptr<const RigAuth> auth);
  ~RecordCheck();
  RecordCheck(const RecordCheck&) = delete;
  RecordCheck& operator=(const RecordCheck&) = delete;

  // False: leave the event out. `utime` is the event's recorded receive time [us].
  bool admit(std::string_view channel, const void* data, std::size_t size, std::int64_t utime);

  bool verifying() const noexcept { return auth_ != nullptr; }
  // Since the last take_notes(): a keyed marker seen, events left out.
  bool marked_keyed() const noexcept { return marked_keyed_; }
  std::uint64_t left_out() const noexcept { return left_out_; }
  std::uint64_t left_out_total() const noexcept { return left_out_total_; }

  // What to tell the reader's user about the events since the last call (one file, say), then
  // starts counting afresh (the senders' counters are kept: a replay across files is caught):
  // "873 message(s) failed signature verification and were left out (HX_COMMAND: 870 unsigned;
  // HX_SENSOR: 3 unsigned)", or "recorded on a keyed rig; signatures not checked (no key given)".
  std::vector<std::string> take_notes();

 private:
  std::shared_ptr<const RigAuth> auth_;
  std::map<std::string, std::unique_ptr<MessageVerifier>, std::less<>> verifiers_;
  std::map<std::string, std::array<std::uint64_t, kAuthResults>, std::less<>> refused_;
  std::uint64_t left_out_ = 0;
  std::uint64_t left_out_total_ = 0;
  bool marked_keyed_ = false;
  bool unmarked_ = false;  // events of a file not marked keyed read with a key: not verified
};

}  // namespace hystloop
