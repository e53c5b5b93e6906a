// Test program for hystloop-logger (tests/integration/logger_*.sh):
//
//   logger_probe publish   --url U --prefix P --blocks N [--block-ticks B] [--gap-at G --gap-len L]
//                          [--commands M] [--rate-hz R] [--wait-logger-s T]
//   logger_probe check-log --prefix P --blocks N [--block-ticks B] [--gap-at G --gap-len L] [--commands M] FILE...
//   logger_probe shutdown  --url U --prefix P          (control_t SHUTDOWN addressed to "logger")
//   logger_probe wait-logger --url U --prefix P [--wait-logger-s T]   (until the logger reports)
//   logger_probe sync      --url U --prefix P [--wait-logger-s T]   (until the logger answers a request sent now)
//   logger_probe read-logs FILE...      (every event of every file, whatever the channel)
//   logger_probe watch-status --url U --prefix P [--seconds S]   (the logger's HX_STATUS as JSON lines)
//
// The stream, round k = 0..N-1: the sensor block of ticks B*k .. B*k + B - 1 (B = 10 by
// default) unless G <= k < G+L (the deliberate gap: L*B ticks from B*G missing), the command
// block answering it (ticks B*k + 500 .. + B - 1) if k < M, and every 100th round
// trajectory(k/100) and params(k/100) (types the logger does not decode: recorded byte-exact
// all the same); values from tests/lcm/message_fixtures.hpp. `publish` first waits until
// the logger's HX_STATUS is heard (it reports once at start), then sends the stream paced
// at R rounds per second. `check-log` reads the files in the order given with lcm::LogFile
// and requires exactly that stream on those channels, in order, byte-identical to the
// fixtures, with event numbers and timestamps non-decreasing in each file. Other channels
// (HX_STATUS) are ignored. `read-logs` reads each file with lcm::LogFile and requires it to
// hold at least one event and to end exactly where its last complete event ends (what
// lcm-logplayer needs to play it to the end); it prints {"files": F, "events": N} with N
// the events read. `watch-status` prints every status of process "logger" for S seconds
// (default 10) as one JSON object a line: {"state", "detail", "counters": {...}}. `sync` sends a
// control request and waits for the logger's answer on HX_STATUS (it reports at once after it
// answers): the logger handles its one socket in order, so once it answered, it has received
// everything published before the request (what a test waits for before stopping it); prints the
// logger's received counters; exit 1 if no answer came within T seconds (default 5).
// Exit status 0 = as expected, 1 = not, 2 = usage.
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <cstring>
#include <string>
#include <thread>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "hystloop/control_t.hpp"
#include "hystloop/service_status_t.hpp"
#include "lcm/channels.hpp"
#include "lcm/connection.hpp"
#include "lcm/message_fixtures.hpp"
#include "lcm/publisher.hpp"
#include "lcm/subscription.hpp"
#include "integration/probe_common.hpp"

namespace hystloop {
namespace {

struct Options {
  std::string mode;
  std::string url;
  std::string prefix{kDefaultRigPrefix};
  std::int64_t blocks = 1000;
  std::int64_t block_ticks = 10;
  std::int64_t gap_at = -1;
  std::int64_t gap_len = 0;
  std::int64_t commands = 0;
  double rate_hz = 2000.0;
  double wait_logger_s = 5.0;
  double seconds = 10.0;
  std::vector<std::string> files;
};

Options parse(int argc, char** argv) {
  Options o;
  o.mode = probe::mode_of(
      argc, argv, "usage: logger_probe publish|check-log|shutdown|wait-logger|sync|read-logs|watch-status [options]");
  probe::parse_options(argc, argv,
                       {{"--url", &o.url},
                        {"--prefix", &o.prefix},
                        {"--blocks", &o.blocks},
                        {"--block-ticks", &o.block_ticks},
                        {"--gap-at", &o.gap_at},
                        {"--gap-len", &o.gap_len},
                        {"--commands", &o.commands},
                        {"--rate-hz", &o.rate_hz},
                        {"--wait-logger-s", &o.wait_logger_s},
                        {"--seconds", &o.seconds}},
                       &o.files);
  if (o.block_ticks < 1 || o.block_ticks > sensor_block_t::MAX_TICKS)
    throw std::invalid_argument("--block-ticks: 1..1000");
  return o;
}

struct Event {
  const std::string* channel;
  std::vector<std::uint8_t> bytes;
};

// The stream in publication order.
std::vector<Event> expected_stream(const Options& o, const ChannelNames& ch) {
  std::vector<Event> events;
  for (std::int64_t k = 0; k < o.blocks; ++k) {
    const std::int64_t seq = o.block_ticks * k;
    if (!(k >= o.gap_at && k < o.gap_at + o.gap_len)) {
      events.push_back({&ch.sensor, fixtures::encode(fixtures::sensor_ticks(seq, o.block_ticks))});
    }
    if (k < o.commands) {
      events.push_back({&ch.command, fixtures::encode(fixtures::command_ticks(
                                         seq + fixtures::kCommandLead, o.block_ticks, seq + o.block_ticks - 1))});
    }
    if (k % 100 == 0) {
      events.push_back({&ch.trajectory, fixtures::encode(fixtures::trajectory(k / 100))});
      events.push_back({&ch.params, fixtures::encode(fixtures::params(k / 100))});
    }
  }
  return events;
}

bool wait_for_logger(lcm::LCM& lcm, const ChannelNames& ch, double timeout_s) {
  bool heard = false;
  Subscription<service_status_t> status(lcm, ch.status, [&](const service_status_t& m, std::int64_t) {
    if (m.process == "logger") heard = true;
  });
  const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  while (!heard && std::chrono::steady_clock::now() < until) handle_pending(lcm, std::chrono::milliseconds(50));
  return heard;
}

int publish(const Options& o) {
  const ChannelNames ch(o.prefix);
  auto lcm = open_lcm(o.url);
  if (!wait_for_logger(*lcm, ch, o.wait_logger_s)) {
    std::fprintf(stderr, "logger_probe: no HX_STATUS from the logger within %.1f s\n", o.wait_logger_s);
    return 1;
  }
  const std::vector<Event> events = expected_stream(o, ch);
  // Pace by rounds: the events of round k go out at start + k / rate.
  const auto start = std::chrono::steady_clock::now();
  std::size_t next = 0;
  std::int64_t round = 0;
  int failures = 0;
  for (std::int64_t k = 0; k < o.blocks; ++k) {
    const auto due = start + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                 std::chrono::duration<double>(static_cast<double>(k) / o.rate_hz));
    std::this_thread::sleep_until(due);
    // The events of round k: as many as expected_stream made for it.
    const std::size_t count = static_cast<std::size_t>(!(k >= o.gap_at && k < o.gap_at + o.gap_len)) +
                              static_cast<std::size_t>(k < o.commands) + (k % 100 == 0 ? 2u : 0u);
    for (std::size_t i = 0; i < count; ++i, ++next) {
      const Event& e = events[next];
      if (lcm->publish(*e.channel, e.bytes.data(), static_cast<unsigned>(e.bytes.size())) != 0) ++failures;
    }
    round = k + 1;
  }
  const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("logger_probe: published %zu messages in %lld rounds over %.3f s (%.0f rounds/s), %d failed\n", next,
              static_cast<long long>(round), elapsed, static_cast<double>(round) / elapsed, failures);
  return failures == 0 ? 0 : 1;
}

int check_log(const Options& o) {
  const ChannelNames ch(o.prefix);
  const std::vector<Event> expected = expected_stream(o, ch);
  const std::string* names[] = {&ch.sensor, &ch.command, &ch.trajectory, &ch.params};
  std::size_t next = 0;
  int errors = 0;
  auto fail = [&](const std::string& what) {
    if (++errors <= 10) std::fprintf(stderr, "logger_probe check-log: %s\n", what.c_str());
  };
  for (const std::string& file : o.files) {
    lcm::LogFile log(file, "r");
    if (!log.good()) {
      fail("cannot open " + file);
      continue;
    }
    std::int64_t last_eventnum = -1;
    // The receive times of one sender's messages never go back; another sender's (the logger's
    // own HX_STATUS, a sync request) may be stamped a little before a packet delivered ahead of
    // it, so the time order is checked on what this probe published.
    std::int64_t last_timestamp = 0;
    std::string last_channel;
    std::size_t events_in_file = 0;
    while (const lcm::LogEvent* ev = log.readNextEvent()) {
      ++events_in_file;
      if (ev->eventnum <= last_eventnum)
        fail(file + ": event numbers not increasing at " + std::to_string(ev->eventnum));
      last_eventnum = ev->eventnum;
      bool ours = false;
      for (const std::string* n : names) ours = ours || ev->channel == *n;
      if (!ours) continue;
      if (ev->timestamp < last_timestamp) {
        std::string what = file;
        what += ": timestamp goes back at event " + std::to_string(ev->eventnum);
        what += " (" + ev->channel + ", " + std::to_string(ev->timestamp) + " us after ";
        what += last_channel + " at " + std::to_string(last_timestamp) + " us)";
        fail(what);
      }
      last_timestamp = ev->timestamp;
      last_channel = ev->channel;
      if (next >= expected.size()) {
        fail(file + ": more messages than published (" + ev->channel + ")");
        continue;
      }
      const Event& want = expected[next];
      if (ev->channel != *want.channel) {
        fail(file + ": message " + std::to_string(next) + " is on " + ev->channel + ", expected " + *want.channel);
      } else if (static_cast<std::size_t>(ev->datalen) != want.bytes.size() ||
                 std::memcmp(ev->data, want.bytes.data(), want.bytes.size()) != 0) {
        fail(file + ": message " + std::to_string(next) + " on " + ev->channel + " differs from what was published");
      }
      ++next;
    }
    if (events_in_file == 0) fail(file + ": no events (rotation must not leave empty files)");
  }
  if (next != expected.size()) {
    fail("found " + std::to_string(next) + " of " + std::to_string(expected.size()) + " published messages");
  }
  std::printf("logger_probe check-log: %zu files, %zu of %zu messages intact and in order, %d errors\n", o.files.size(),
              next, expected.size(), errors);
  return errors == 0 ? 0 : 1;
}

int read_logs(const Options& o) {
  std::uint64_t events = 0;
  int errors = 0;
  for (const std::string& file : o.files) {
    lcm::LogFile log(file, "r");
    if (!log.good()) {
      std::fprintf(stderr, "logger_probe read-logs: cannot open %s\n", file.c_str());
      ++errors;
      continue;
    }
    std::uint64_t in_file = 0;
    std::uint64_t bytes = 0;  // LCM's framing: 28 bytes + channel + data per event
    while (const lcm::LogEvent* ev = log.readNextEvent()) {
      ++in_file;
      bytes += 28u + ev->channel.size() + static_cast<std::uint64_t>(ev->datalen);
    }
    const std::uint64_t size = std::filesystem::file_size(file);
    if (in_file == 0 || bytes != size) {
      std::fprintf(stderr, "logger_probe read-logs: %s: %llu events read, ending at byte %llu of %llu\n", file.c_str(),
                   static_cast<unsigned long long>(in_file), static_cast<unsigned long long>(bytes),
                   static_cast<unsigned long long>(size));
      ++errors;
    }
    events += in_file;
  }
  std::printf("{\"files\": %zu, \"events\": %llu, \"errors\": %d}\n", o.files.size(),
              static_cast<unsigned long long>(events), errors);
  return errors == 0 ? 0 : 1;
}

std::string json_text(const std::string& text) {
  std::string out = "\"";
  for (const char c : text) {
    const auto b = static_cast<unsigned char>(c);
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (b < 0x20 || b >= 0x7f) {
      char hex[8];
      std::snprintf(hex, sizeof hex, "\\u%04x", static_cast<unsigned>(b));
      out += hex;
    } else {
      out += c;
    }
  }
  return out + "\"";
}

int watch_status(const Options& o) {
  const ChannelNames ch(o.prefix);
  auto lcm = open_lcm(o.url);
  Subscription<service_status_t> status(*lcm, ch.status, [&](const service_status_t& m, std::int64_t) {
    if (m.process != "logger") return;
    std::string line =
        "{\"state\": " + std::to_string(m.state) + ", \"detail\": " + json_text(m.detail) + ", \"counters\": {";
    for (int i = 0; i < m.n_counters; ++i) {
      line += (i ? ", " : "") + json_text(m.counter_names[i]) + ": " + std::to_string(m.counter_values[i]);
    }
    std::printf("%s}}\n", line.c_str());
    std::fflush(stdout);
  });
  const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(o.seconds);
  while (std::chrono::steady_clock::now() < until) handle_pending(*lcm, std::chrono::milliseconds(50));
  return 0;
}

int wait_logger(const Options& o) {
  const ChannelNames ch(o.prefix);
  auto lcm = open_lcm(o.url);
  if (wait_for_logger(*lcm, ch, o.wait_logger_s)) return 0;
  std::fprintf(stderr, "logger_probe: no HX_STATUS from the logger within %.1f s\n", o.wait_logger_s);
  return 1;
}

// RESET_COUNTERS to every process: the logger answers it as done (its counters describe the whole
// recording and do not reset), so nothing about the recording changes but the request itself.
int sync_logger(const Options& o) {
  const ChannelNames ch(o.prefix);
  auto lcm = open_lcm(o.url);
  const std::int64_t now_us =
      std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::system_clock::now().time_since_epoch())
          .count();
  control_t msg{};
  msg.utime = now_us;
  msg.request_id = now_us;  // unique per call (0 is never acted on)
  msg.command = control_t::RESET_COUNTERS;
  bool answered = false;
  std::string received;
  Subscription<service_status_t> status(*lcm, ch.status, [&](const service_status_t& m, std::int64_t) {
    if (m.process != "logger") return;
    bool acted = false;
    std::string counts;
    for (int i = 0; i < m.n_counters; ++i) {
      const std::string& name = m.counter_names[static_cast<std::size_t>(i)];
      const std::int64_t value = m.counter_values[static_cast<std::size_t>(i)];
      if (name == "control_acted_request" && value == msg.request_id) acted = true;
      if (name.size() > 9 && name.compare(name.size() - 9, 9, ".received") == 0) {
        counts += " " + name + "=" + std::to_string(value);
      }
    }
    if (acted && !answered) {
      answered = true;
      received = counts;
    }
  });
  Publisher<control_t> publisher(*lcm, ch.control);
  // Sent again every 0.5 s while unanswered, as senders do over UDP (the logger acts once per id).
  const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(o.wait_logger_s);
  auto next_send = std::chrono::steady_clock::now();
  while (!answered && std::chrono::steady_clock::now() < until) {
    if (std::chrono::steady_clock::now() >= next_send) {
      if (!publisher.publish(msg)) std::fprintf(stderr, "logger_probe sync: publishing the request failed\n");
      next_send += std::chrono::milliseconds(500);
    }
    handle_pending(*lcm, std::chrono::milliseconds(20));
  }
  if (!answered) {
    std::fprintf(stderr, "logger_probe sync: the logger did not answer request %lld within %.1f s\n",
                 static_cast<long long>(msg.request_id), o.wait_logger_s);
    return 1;
  }
  std::printf("logger_probe sync: the logger answered;%s\n", received.c_str());
  return 0;
}

int shutdown(const Options& o) {
  const ChannelNames ch(o.prefix);
  auto lcm = open_lcm(o.url);
  return probe::send_shutdown(*lcm, ch.control, "logger", fixtures::kBaseUtime) ? 0 : 1;
}

int run(int argc, char** argv) {
  return probe::run_mode("logger_probe", parse(argc, argv),
                         {{"publish", publish},
                          {"check-log", check_log},
                          {"shutdown", shutdown},
                          {"wait-logger", wait_logger},
                          {"sync", sync_logger},
                          {"read-logs", read_logs},
                          {"watch-status", watch_status}});
}

}  // namespace
}  // namespace hystloop

int main(int argc, char** argv) {
  return hystloop::probe::run_probe("logger_probe", [&] { return hystloop::run(argc, argv); });
}
