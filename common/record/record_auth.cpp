#include "record/record_auth.hpp"

#include <climits>
#include <cmath>
#include <limits>
#include <utility>

#include <unistd.h>

#include "hystloop/service_status_t.hpp"
#include "lcm/message_checks.hpp"
#include "lcm/message_storage.hpp"
#include "lcm/wire_layout.hpp"

namespace hystloop {

namespace {
constexpr const char* kKeyedCounter = "keyed";

bool is_record_channel(std::string_view channel) noexcept {
  return channel.size() > kRecordSuffix.size() && channel.ends_with(kRecordSuffix) &&
         channel[channel.size() - kRecordSuffix.size() - 1] == '_';
}
}  // namespace

AuthResult verify_recorded(MessageVerifier& verifier, std::string_view channel, const void* data, std::size_t size,
                           std::int64_t now_us) noexcept {
  const auto* bytes = static_cast<const unsigned char*>(data);
  if (size < kAuthTrailerBytes || !has_auth_magic(bytes + size - kAuthTrailerBytes, kAuthTrailerBytes)) {
    return AuthResult::kUnsigned;
  }
  const std::size_t body = size - kAuthTrailerBytes;
  return verifier.verify(channel, bytes, body, bytes + body, kAuthTrailerBytes, now_us);
}

std::vector<std::uint8_t> keyed_record_marker(std::int64_t utime) {
  service_status_t m{};
  m.utime = utime;
  m.process = "logger";
  m.pid = static_cast<std::int32_t>(::getpid());
  m.state = service_status_t::HEALTHY;
  m.detail =
      "recorded on a keyed rig: messages on signed channels whose signature failed are not in this log "
      "(counted on the logger's HX_STATUS and in its summary)";
  m.start_utime = utime;
  m.n_counters = 1;
  m.counter_names = {kKeyedCounter};
  m.counter_values = {1};
  const double nan = std::numeric_limits<double>::quiet_NaN();
  m.loop_p50_us = m.loop_p99_us = m.loop_max_us = nan;
  m.latency_p50_us = m.latency_p99_us = m.latency_max_us = nan;
  std::vector<std::uint8_t> out(static_cast<std::size_t>(m.getEncodedSize()));
  m.encode(out.data(), 0, static_cast<int>(out.size()));
  return out;
}

bool is_keyed_record_marker(std::string_view channel, const void* data, std::size_t size) noexcept {
  if (!is_record_channel(channel) || size < 8 || size > static_cast<std::size_t>(INT_MAX)) return false;
  if (wire_fingerprint(data, size) != service_status_t::getHash()) return false;
  const std::int64_t body = lcm_body_size(wire_layout_of<service_status_t>(), data, size);
  if (body < 0) return false;
  try {
    service_status_t m;
    if (m.decode(data, 0, static_cast<int>(body)) != static_cast<int>(body)) return false;
    if (check_message(m) != Verdict::kOk) return false;
    for (std::size_t i = 0; i < m.counter_names.size(); ++i) {
      if (m.counter_names[i] == kKeyedCounter) return m.counter_values[i] != 0;
    }
  } catch (...) {  // a marker that does not decode says nothing
  }
  return false;
}

RecordCheck::RecordCheck(std::shared_ptr<const RigAuth> auth) : auth_(std::move(auth)) {}
RecordCheck::~RecordCheck() = default;

bool RecordCheck::admit(std::string_view channel, const void* data, std::size_t size, std::int64_t utime) {
  if (is_keyed_record_marker(channel, data, size)) marked_keyed_ = true;
  if (auth_ == nullptr || !is_authenticated_channel(channel)) return true;
  // A file that does not start keyed was recorded without the key: it holds no signatures to
  // check (every message would fail), and nothing recorded it as a keyed rig's.
  if (!marked_keyed_) {
    unmarked_ = true;
    return true;
  }
  auto v = verifiers_.find(channel);
  if (v == verifiers_.end()) {
    // A recorded message is checked at the time it was received (its event time); anything the
    // rig signed before the recording started is as good as what it signed during it.
    v = verifiers_.emplace(std::string(channel), std::make_unique<MessageVerifier>(auth_->key, auth_->max_skew_us))
            .first;
  }
  const AuthResult result = verify_recorded(*v->second, channel, data, size, utime);
  if (result == AuthResult::kOk) return true;
  auto r = refused_.find(channel);
  if (r == refused_.end()) r = refused_.emplace(std::string(channel), std::array<std::uint64_t, kAuthResults>{}).first;
  ++r->second[static_cast<std::size_t>(result)];
  ++left_out_;
  ++left_out_total_;
  return false;
}

std::vector<std::string> RecordCheck::take_notes() {
  std::vector<std::string> notes;
  if (left_out_ > 0) {
    std::string detail;
    for (const auto& [channel, counts] : refused_) {
      std::string reasons;
      for (std::size_t i = 1; i < kAuthResults; ++i) {
        if (counts[i] == 0) continue;
        if (!reasons.empty()) reasons += ", ";
        reasons += std::to_string(counts[i]);
        reasons += " ";
        reasons += to_string(static_cast<AuthResult>(i));
      }
      if (!detail.empty()) detail += "; ";
      detail += channel;
      detail += ": ";
      detail += reasons;
    }
    notes.push_back(std::to_string(left_out_) + " message(s) failed signature verification and were left out (" +
                    detail + ")");
  }
  if (marked_keyed_ && auth_ == nullptr) {
    notes.emplace_back("recorded on a keyed rig; signatures not checked (give the rig key, --key-file, to verify)");
  }
  if (unmarked_) notes.emplace_back("recorded without a rig key (no keyed marker): nothing to verify, read as it is");
  unmarked_ = false;
  refused_.clear();
  left_out_ = 0;
  marked_keyed_ = false;
  return notes;
}

}  // namespace hystloop
