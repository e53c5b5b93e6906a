#include "logger/logger_summary.hpp"

#include <spdlog/fmt/fmt.h>

#include "core/escape.hpp"
#include "runtime/summary_file.hpp"
#include "core/saturating.hpp"

namespace hystloop {

namespace {

struct Totals {
  std::uint64_t received = 0, written = 0, dropped = 0, bytes_written = 0, gap_events = 0, missing = 0, skipped = 0;
  std::uint64_t contract_violations = 0;
  std::uint64_t queue_full = 0, oversize = 0, write_failed = 0;
};

// Each channel's counts saturate; so do their sums (two channels at 2^63 ticks missing must not
// add up to a total of 0).
Totals totals_of(const ChannelTable& channels) {
  Totals t;
  for (std::size_t i = 0; i < channels.size(); ++i) {
    const ChannelSlot& c = channels[i];
    add_saturating(t.received, c.received);
    add_saturating(t.written, c.written.load());
    add_saturating(t.dropped, c.dropped());
    add_saturating(t.bytes_written, c.bytes_written.load());
    add_saturating(t.gap_events, c.sequence.gap_events());
    add_saturating(t.missing, c.sequence.missing());
    add_saturating(t.skipped, c.sequence.skipped());
    add_saturating(t.contract_violations, c.sequence.violations());
    add_saturating(t.queue_full, c.dropped_queue_full);
    add_saturating(t.oversize, c.dropped_oversize);
    add_saturating(t.write_failed, c.write_failed.load());
  }
  return t;
}
}  // namespace

std::string summary_json(const RecordingSummary& s, const ChannelTable& channels) {
  using Json = nlohmann::ordered_json;
  const Totals t = totals_of(channels);
  Json files = Json::array();
  for (const LogFileInfo& f : s.files)
    files.push_back({{"path", f.path.string()}, {"events", f.events}, {"bytes", f.bytes}});
  const DiskFaults& d = s.disk;
  const UnknownChannels& u = channels.unknown();
  Json first_unknown = Json::array();
  for (std::size_t i = 0; i < u.kept_count(); ++i) first_unknown.push_back(std::string(u.kept_name(i)));
  Json per_channel = Json::object();
  for (std::size_t i = 0; i < channels.size(); ++i) {
    const ChannelSlot& c = channels[i];
    Json ch = {{"received", c.received},
               {"bytes_received", c.bytes_received},
               {"written", c.written.load()},
               {"bytes_written", c.bytes_written.load()},
               {"dropped", c.dropped()},
               {"dropped_queue_full", c.dropped_queue_full},
               {"dropped_oversize", c.dropped_oversize},
               {"write_failed", c.write_failed.load()}};
    if (c.verified) {
      Json refused = Json::object();
      for (std::size_t r = 1; r < kAuthResults; ++r) {
        refused[std::string(to_string(static_cast<AuthResult>(r)))] = c.refused[r];
      }
      ch["refused"] = refused;
    }
    if (c.kind != SequenceKind::kNone) {
      const SequenceGapDetector& q = c.sequence;
      Json violations = Json::object();
      for (std::size_t v = 0; v < SequenceGapDetector::kViolationKinds; ++v) {
        const auto reason = static_cast<SequenceGapDetector::Violation>(v);
        violations[std::string(SequenceGapDetector::to_string(reason))] = q.violations(reason);
      }
      Json gaps = Json::array();
      for (std::size_t g = 0; g < q.kept_gap_count(); ++g) {
        gaps.push_back({q.kept_gaps()[g].first_missing, q.kept_gaps()[g].last_missing});
      }
      ch["sequence"] = {{"blocks", q.observed()},
                        {"ticks", q.ticks()},
                        {"first_seq", q.first_seq()},
                        {"last_seq", q.last_seq()},
                        {"gap_events", q.gap_events()},
                        {"missing", q.missing()},
                        {"resumes", q.resumes()},
                        {"skipped", q.skipped()},
                        {"overlaps", q.overlaps()},
                        {"overlap_ticks", q.overlap_ticks()},
                        {"duplicates", q.duplicates()},
                        {"out_of_order", q.out_of_order()},
                        {"restarts", q.restarts()},
                        {"undecodable", c.undecodable},
                        {"contract_violations", violations},
                        {"gaps", gaps}};
    }
    per_channel[std::string(c.name_view())] = ch;
  }
  const Json j = {
      {"recording", s.recording},
      {"keyed", s.keyed},
      {"start_utime", s.start_utime},
      {"stop_utime", s.stop_utime},
      {"duration_s", s.duration_s},
      {"stop_reason", s.stop_reason},
      {"files", files},
      {"totals",
       {{"received", t.received},
        {"written", t.written},
        {"dropped", saturating_add(t.dropped, s.unrecorded_channel)},
        {"bytes_written", t.bytes_written},
        {"gap_events", t.gap_events},
        {"missing", t.missing},
        {"skipped", t.skipped},
        {"contract_violations", t.contract_violations}}},
      {"dropped",
       {{"queue_full", t.queue_full},
        {"oversize", t.oversize},
        {"write_failed", t.write_failed},
        {"unrecorded_channel", s.unrecorded_channel}}},
      {"disk",
       {{"ok", d.errors == 0},
        {"errors", d.errors},
        {"last_error", d.errors == 0 ? std::string() : d.reason()},
        {"events_lost", d.events_lost},
        {"files_truncated", d.files_truncated},
        {"files_removed", d.files_removed},
        {"unconfirmed_events", d.unconfirmed_events},
        {"recoveries", d.recoveries}}},
      {"unknown_channels",
       {{"messages", u.messages()},
        {"distinct", u.distinct()},
        {"distinct_is_lower_bound", u.distinct_is_lower_bound()},
        {"first", first_unknown}}},
      {"queue", {{"capacity_bytes", s.queue_capacity_bytes}, {"high_water_bytes", s.queue_high_water_bytes}}},
      {"process",
       {{"cpu_user_s", s.cpu_user_s}, {"cpu_system_s", s.cpu_system_s}, {"peak_rss_bytes", s.peak_rss_bytes}}},
      {"channels", per_channel},
  };
  return to_json_text(j);
}

std::vector<std::string> summary_lines(const RecordingSummary& s, const ChannelTable& channels) {
  const Totals t = totals_of(channels);
  std::vector<std::string> lines;
  lines.push_back(fmt::format(
      "recorded {} of {} messages ({} payload bytes) in {} file(s) over {:.1f} s, stopped by {}; dropped {} (queue "
      "full {}, oversize {}, write failed {}, no channel slot {})",
      t.written, t.received, t.bytes_written, s.files.size(), s.duration_s, s.stop_reason,
      saturating_add(t.dropped, s.unrecorded_channel), t.queue_full, t.oversize, t.write_failed, s.unrecorded_channel));
  if (s.disk.errors > 0) {
    lines.push_back(fmt::format(
        "  DISK FAULT: {} failed call(s), last {}; {} events not written, {} file(s) cut back to their last complete "
        "event, {} empty file(s) removed, {} events unconfirmed (fsync/close failed)",
        s.disk.errors, s.disk.reason(), s.disk.events_lost, s.disk.files_truncated, s.disk.files_removed,
        s.disk.unconfirmed_events));
  }
  if (const UnknownChannels& u = channels.unknown(); u.messages() > 0) {
    std::string names;
    for (std::size_t i = 0; i < u.kept_count(); ++i) names += (i ? ", '" : "'") + escape_wire(u.kept_name(i)) + "'";
    lines.push_back(fmt::format("  not recorded: {} message(s) on {}{} channel(s) without a slot (first: {})",
                                u.messages(), u.distinct_is_lower_bound() ? ">= " : "", u.distinct(), names));
  }
  for (std::size_t i = 0; i < channels.size(); ++i) {
    const ChannelSlot& c = channels[i];
    std::string line = fmt::format("  {}: received {}, written {}, dropped {}", escape_wire(c.name_view()), c.received,
                                   c.written.load(), c.dropped());
    if (c.kind != SequenceKind::kNone) {
      const SequenceGapDetector& q = c.sequence;
      line += fmt::format(", ticks {}..{}, gaps {} (missing {} ticks), overlaps {}, duplicates {}, out of order {}",
                          q.first_seq(), q.last_seq(), q.gap_events(), q.missing(), q.overlaps(), q.duplicates(),
                          q.out_of_order());
      if (q.resumes() > 0) line += fmt::format(", resumes {} (skipped {} ticks)", q.resumes(), q.skipped());
      if (q.restarts() > 0) line += fmt::format(", restarts {}", q.restarts());
      if (c.undecodable > 0) line += fmt::format(", undecodable {}", c.undecodable);
      if (q.violations() > 0) {
        line += fmt::format(", contract violations {} (not checked for gaps:", q.violations());
        for (std::size_t v = 0; v < SequenceGapDetector::kViolationKinds; ++v) {
          const auto reason = static_cast<SequenceGapDetector::Violation>(v);
          line += fmt::format(" {} {}", SequenceGapDetector::to_string(reason), q.violations(reason));
        }
        line += ")";
      }
    }
    lines.push_back(line);
  }
  for (const LogFileInfo& f : s.files) {
    lines.push_back(fmt::format("  file {}: {} events, {} bytes", f.path.string(), f.events, f.bytes));
  }
  return lines;
}

}  // namespace hystloop
