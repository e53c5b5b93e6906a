#include "run_data.hpp"

namespace hystloop::report {

void CommandVersions::add(std::int64_t seq, std::int32_t version, std::int8_t mode) {
  if (!runs_.empty()) {
    VersionRun& last = runs_.back();
    if (seq < last.end_seq) return;  // a re-send: the first logged command wins
    if (seq == last.end_seq && version == last.version && mode == last.mode) {
      ++last.end_seq;
      return;
    }
  }
  runs_.push_back({seq, seq + 1, version, mode});
}

const VersionRun* CommandVersions::run_at(std::int64_t seq) const noexcept {
  const auto it = std::upper_bound(runs_.begin(), runs_.end(), seq,
                                   [](std::int64_t s, const VersionRun& r) { return s < r.first_seq; });
  if (it == runs_.begin()) return nullptr;
  const VersionRun& run = *(it - 1);
  return seq < run.end_seq ? &run : nullptr;
}

std::optional<std::int32_t> CommandVersions::at(std::int64_t seq) const noexcept {
  const VersionRun* run = run_at(seq);
  return run != nullptr ? std::optional<std::int32_t>(run->version) : std::nullopt;
}

}  // namespace hystloop::report
