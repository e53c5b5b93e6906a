#include "reident/params_in_use.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

namespace hystloop {

std::string_view to_string(ParamsOffer offer) noexcept {
  switch (offer) {
    case ParamsOffer::adopted: return "adopted";
    case ParamsOffer::echo: return "echo";
    case ParamsOffer::stale: return "stale";
    case ParamsOffer::invalid: return "invalid";
    case ParamsOffer::forged: return "forged";
    case ParamsOffer::other_axis: return "other_axis";
  }
  return "unknown";
}

ParamsInUse::ParamsInUse(const MemParams& initial, std::string own_source, std::int64_t own_publisher_id)
    : params_(initial), own_publisher_id_(own_publisher_id), own_source_(std::move(own_source)) {
  params_.validate();
}

namespace {
bool in_domain(const MemParams& p) noexcept {
  return std::isfinite(p.c1) && std::isfinite(p.c2) && std::isfinite(p.c3) && p.c1 > 0.0 && p.c2 >= 0.0 && p.c3 > 0.0;
}
}  // namespace

void ParamsInUse::follow(std::int32_t version) noexcept {
  if (version < kFollowLimit) highest_seen_ = std::max(highest_seen_, version);
}

ParamsOffer ParamsInUse::offer(const MemParams& params, std::int32_t version, std::int64_t publisher_id, bool valid,
                               std::string_view source) noexcept {
  if (publisher_id == own_publisher_id_) {
    if (published(version)) return ParamsOffer::echo;
    follow(version);  // our next set numbers above it: the compensator takes ours again
    ++forged_sets_;
    last_forged_version_ = version;
    return ParamsOffer::forged;
  }
  follow(version);
  if (!valid || !in_domain(params)) return ParamsOffer::invalid;
  if (!admission_.is_new(publisher_id, version)) return ParamsOffer::stale;
  admission_.accept(publisher_id, version);
  params_ = params;
  version_ = version;
  ++generation_;
  source_.assign(source.begin(), source.end());  // off the per-sample path (HX_PARAMS is rare)
  return ParamsOffer::adopted;
}

void ParamsInUse::on_command(std::int64_t seq, std::int32_t params_version) noexcept {
  follow(params_version);
  applied_.record(seq, params_version);
}

std::int32_t ParamsInUse::on_sample(std::int64_t seq) noexcept {
  applied_version_ = applied_.at(seq);
  applied_.forget_before(seq);
  return applied_version_;
}

bool ParamsInUse::published(std::int32_t version) const noexcept {
  if (version < 1 || version > own_published_) return false;
  return std::find(sent_.begin(), sent_.end(), version) != sent_.end();
}

std::int32_t ParamsInUse::claim_version() noexcept {
  const std::int32_t top = std::max({highest_seen_, own_published_, version_ < kFollowLimit ? version_ : 0});
  const std::int32_t next = top < std::numeric_limits<std::int32_t>::max() ? top + 1 : top;
  highest_seen_ = next;
  own_published_ = next;
  sent_[sent_next_] = next;
  sent_next_ = (sent_next_ + 1) % kSentKept;
  return next;
}

std::int32_t ParamsInUse::adopt_own(const MemParams& params) noexcept {
  params_ = params;
  version_ = claim_version();
  ++generation_;
  source_ = own_source_;
  return version_;
}

}  // namespace hystloop
