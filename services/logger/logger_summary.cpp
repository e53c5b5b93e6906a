#include "logger/logger_summary.hpp"

#include <cstdio>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <system_error>

#include "core/escape.hpp"
#include "core/saturating.hpp"

namespace hystloop {

namespace {
std::string json_string(std::string_view text) {
  std::string out = "\"";
  for (const char c : text) {
    switch (c) {
      case '"': out += "\\\""; break;
      case '\\': out += "\\\\"; break;
      case '\n': out += "\\n"; break;
      case '\t': out += "\\t"; break;
      default:
        if (static_cast<unsigned char>(c) < 0x20 ||
            static_cast<unsigned char>(c) >= 0x7f) {  // keep the JSON valid UTF-8
          char escaped[8];
          std::snprintf(escaped, sizeof escaped, "\\u%04x", static_cast<unsigned>(static_cast<unsigned char>(c)));
          out += escaped;
        } else {
          out += c;
        }
    }
  }
  return out + "\"";
}

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
  const Totals t = totals_of(channels);
  std::ostringstream j;
  j.precision(6);
  j << std::fixed;
  j << "{\n  \"recording\": " << json_string(s.recording) << ",\n  \"start_utime\": " << s.start_utime
    << ",\n  \"stop_utime\": " << s.stop_utime << ",\n  \"duration_s\": " << s.duration_s
    << ",\n  \"stop_reason\": " << json_string(s.stop_reason) << ",\n  \"files\": [";
  for (std::size_t i = 0; i < s.files.size(); ++i) {
    const LogFileInfo& f = s.files[i];
    j << (i ? "," : "") << "\n    {\"path\": " << json_string(f.path.string()) << ", \"events\": " << f.events
      << ", \"bytes\": " << f.bytes << "}";
  }
  j << "\n  ],\n  \"totals\": {\"received\": " << t.received << ", \"written\": " << t.written
    << ", \"dropped\": " << saturating_add(t.dropped, s.unrecorded_channel)
    << ", \"bytes_written\": " << t.bytes_written << ", \"gap_events\": " << t.gap_events
    << ", \"missing\": " << t.missing << ", \"skipped\": " << t.skipped
    << ", \"contract_violations\": " << t.contract_violations << "},\n";
  j << "  \"dropped\": {\"queue_full\": " << t.queue_full << ", \"oversize\": " << t.oversize
    << ", \"write_failed\": " << t.write_failed << ", \"unrecorded_channel\": " << s.unrecorded_channel << "},\n";
  const DiskFaults& d = s.disk;
  j << "  \"disk\": {\"ok\": " << (d.errors == 0 ? "true" : "false") << ", \"errors\": " << d.errors
    << ", \"last_error\": " << json_string(d.errors == 0 ? "" : d.reason()) << ", \"events_lost\": " << d.events_lost
    << ", \"files_truncated\": " << d.files_truncated << ", \"files_removed\": " << d.files_removed
    << ", \"unconfirmed_events\": " << d.unconfirmed_events << ", \"recoveries\": " << d.recoveries << "},\n";
  const UnknownChannels& u = channels.unknown();
  j << "  \"unknown_channels\": {\"messages\": " << u.messages() << ", \"distinct\": " << u.distinct()
    << ", \"distinct_is_lower_bound\": " << (u.distinct_is_lower_bound() ? "true" : "false") << ", \"first\": [";
  for (std::size_t i = 0; i < u.kept_count(); ++i) j << (i ? ", " : "") << json_string(u.kept_name(i));
  j << "]},\n";
  j << "  \"queue\": {\"capacity_bytes\": " << s.queue_capacity_bytes
    << ", \"high_water_bytes\": " << s.queue_high_water_bytes << "},\n";
  j << "  \"process\": {\"cpu_user_s\": " << s.cpu_user_s << ", \"cpu_system_s\": " << s.cpu_system_s
    << ", \"peak_rss_bytes\": " << s.peak_rss_bytes << "},\n  \"channels\": {";
  for (std::size_t i = 0; i < channels.size(); ++i) {
    const ChannelSlot& c = channels[i];
    j << (i ? "," : "") << "\n    " << json_string(c.name_view()) << ": {\"received\": " << c.received
      << ", \"bytes_received\": " << c.bytes_received << ", \"written\": " << c.written.load()
      << ", \"bytes_written\": " << c.bytes_written.load() << ", \"dropped\": " << c.dropped()
      << ", \"dropped_queue_full\": " << c.dropped_queue_full << ", \"dropped_oversize\": " << c.dropped_oversize
      << ", \"write_failed\": " << c.write_failed.load();
    if (c.kind != SequenceKind::kNone) {
      const SequenceGapDetector& q = c.sequence;
      j << ",\n      \"sequence\": {\"blocks\": " << q.observed() << ", \"ticks\": " << q.ticks()
        << ", \"first_seq\": " << q.first_seq() << ", \"last_seq\": " << q.last_seq()
        << ", \"gap_events\": " << q.gap_events() << ", \"missing\": " << q.missing()
        << ", \"resumes\": " << q.resumes() << ", \"skipped\": " << q.skipped() << ", \"overlaps\": " << q.overlaps()
        << ", \"overlap_ticks\": " << q.overlap_ticks() << ", \"duplicates\": " << q.duplicates()
        << ", \"out_of_order\": " << q.out_of_order() << ", \"restarts\": " << q.restarts()
        << ", \"undecodable\": " << c.undecodable << ", \"contract_violations\": {";
      for (std::size_t v = 0; v < SequenceGapDetector::kViolationKinds; ++v) {
        const auto reason = static_cast<SequenceGapDetector::Violation>(v);
        j << (v ? ", " : "") << "\"" << SequenceGapDetector::to_string(reason) << "\": " << q.violations(reason);
      }
      j << "}, \"gaps\": [";
      for (std::size_t g = 0; g < q.kept_gap_count(); ++g) {
        j << (g ? ", " : "") << "[" << q.kept_gaps()[g].first_missing << ", " << q.kept_gaps()[g].last_missing << "]";
      }
      j << "]}";
    }
    j << "}";
  }
  j << "\n  }\n}\n";
  return j.str();
}

std::vector<std::string> summary_lines(const RecordingSummary& s, const ChannelTable& channels) {
  const Totals t = totals_of(channels);
  std::vector<std::string> lines;
  std::ostringstream head;
  head.precision(1);
  head << std::fixed << "recorded " << t.written << " of " << t.received << " messages (" << t.bytes_written
       << " payload bytes) in " << s.files.size() << " file(s) over " << s.duration_s << " s, stopped by "
       << s.stop_reason << "; dropped " << saturating_add(t.dropped, s.unrecorded_channel) << " (queue full "
       << t.queue_full << ", oversize " << t.oversize << ", write failed " << t.write_failed << ", no channel slot "
       << s.unrecorded_channel << ")";
  lines.push_back(head.str());
  if (s.disk.errors > 0) {
    lines.push_back("  DISK FAULT: " + std::to_string(s.disk.errors) + " failed call(s), last " + s.disk.reason() +
                    "; " + std::to_string(s.disk.events_lost) + " events not written, " +
                    std::to_string(s.disk.files_truncated) + " file(s) cut back to their last complete event, " +
                    std::to_string(s.disk.files_removed) + " empty file(s) removed, " +
                    std::to_string(s.disk.unconfirmed_events) + " events unconfirmed (fsync/close failed)");
  }
  if (channels.unknown().messages() > 0) {
    const UnknownChannels& u = channels.unknown();
    std::string names;
    for (std::size_t i = 0; i < u.kept_count(); ++i) names += (i ? ", '" : "'") + escape_wire(u.kept_name(i)) + "'";
    lines.push_back("  not recorded: " + std::to_string(u.messages()) + " message(s) on " +
                    (u.distinct_is_lower_bound() ? ">= " : "") + std::to_string(u.distinct()) +
                    " channel(s) without a slot (first: " + names + ")");
  }
  for (std::size_t i = 0; i < channels.size(); ++i) {
    const ChannelSlot& c = channels[i];
    std::ostringstream line;
    line << "  " << escape_wire(c.name_view()) << ": received " << c.received << ", written " << c.written.load()
         << ", dropped " << c.dropped();
    if (c.kind != SequenceKind::kNone) {
      const SequenceGapDetector& q = c.sequence;
      line << ", ticks " << q.first_seq() << ".." << q.last_seq() << ", gaps " << q.gap_events() << " (missing "
           << q.missing() << " ticks), overlaps " << q.overlaps() << ", duplicates " << q.duplicates()
           << ", out of order " << q.out_of_order();
      if (q.resumes() > 0) line << ", resumes " << q.resumes() << " (skipped " << q.skipped() << " ticks)";
      if (q.restarts() > 0) line << ", restarts " << q.restarts();
      if (c.undecodable > 0) line << ", undecodable " << c.undecodable;
      if (q.violations() > 0) {
        line << ", contract violations " << q.violations() << " (not checked for gaps:";
        for (std::size_t v = 0; v < SequenceGapDetector::kViolationKinds; ++v) {
          const auto reason = static_cast<SequenceGapDetector::Violation>(v);
          line << " " << SequenceGapDetector::to_string(reason) << " " << q.violations(reason);
        }
        line << ")";
      }
    }
    lines.push_back(line.str());
  }
  for (const LogFileInfo& f : s.files) {
    lines.push_back("  file " + f.path.string() + ": " + std::to_string(f.events) + " events, " +
                    std::to_string(f.bytes) + " bytes");
  }
  return lines;
}

void write_file_atomically(const std::filesystem::path& path, const std::string& text) {
  const std::filesystem::path tmp = path.string() + ".tmp";
  std::error_code ec;
  const auto fail = [&](const std::string& what) {
    std::filesystem::remove(tmp, ec);  // no stray temporary file left behind
    throw std::runtime_error(what);
  };
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) fail("cannot write " + tmp.string());
    out << text;
    out.flush();
    if (!out) fail("cannot write " + tmp.string() + " (disk full?)");
  }
  std::filesystem::rename(tmp, path, ec);
  if (ec) fail("cannot rename " + tmp.string() + " to " + path.string() + ": " + ec.message());
}

}  // namespace hystloop
