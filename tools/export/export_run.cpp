#include "export_run.hpp"

#include <unistd.h>

#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>

#include <yaml-cpp/yaml.h>

#include "core/clock.hpp"
#include "core/errors.hpp"
#include "decode.hpp"
#include "event_file.hpp"
#include "hdf5_file.hpp"
#include "lcm/channels.hpp"
#include "log_reader.hpp"

namespace hystloop::exporter {

namespace fs = std::filesystem;

namespace {

// Reports how far reading got, at most every two seconds.
class Progress {
 public:
  Progress(std::FILE* out, const std::vector<fs::path>& logs) : out_(out) {
    for (const auto& f : logs) {
      std::error_code ec;
      const auto size = fs::file_size(f, ec);
      if (!ec) total_bytes_ += static_cast<double>(size);
    }
  }
  void event(const lcm::LogEvent& e) {
    ++events_;
    bytes_ += 28.0 + static_cast<double>(e.channel.size()) + static_cast<double>(e.datalen);  // header + body
    if (out_ == nullptr || (events_ & 0xfff) != 0) return;
    const double now_s = monotonic_s();
    if (now_s - last_s_ < 2.0) return;  // a line every 2 s at most
    last_s_ = now_s;
    std::fprintf(out_, "hystloop-export: read %.0f %% of %.1f MB (%llu events)\n",
                 total_bytes_ > 0 ? 100.0 * bytes_ / total_bytes_ : 100.0, total_bytes_ * 1e-6,
                 static_cast<unsigned long long>(events_));
  }

 private:
  std::FILE* out_;
  double total_bytes_ = 0.0, bytes_ = 0.0;
  unsigned long long events_ = 0;
  double last_s_ = monotonic_s();
};

// The processes that reported on a status channel: "bridge@stage-pc pid 41 started 1700000000000000".
std::string processes(const std::vector<ChannelTable>& tables) {
  std::set<std::string> seen;
  std::string out;
  for (const ChannelTable& t : tables) {
    if (t.type_name != "hystloop.service_status_t") continue;
    const Column* process = t.find("process");
    const Column* host = t.find("host");
    const Column* pid = t.find("pid");
    const Column* start = t.find("start_utime_us");
    if (process == nullptr || host == nullptr || pid == nullptr || start == nullptr) continue;
    for (std::size_t r = 0; r < t.rows; ++r) {
      const std::string line = process->text[r] + '@' + host->text[r] + " pid " + std::to_string(pid->i64[r]) +
                               " started " + std::to_string(start->i64[r]) + " (" + t.channel + ")";
      if (seen.insert(line).second) out += (out.empty() ? "" : "\n") + line;
    }
  }
  return out;
}

std::string joined(const std::vector<std::string>& lines) {
  std::string out;
  for (const auto& l : lines) out += (out.empty() ? "" : "\n") + l;
  return out;
}

}  // namespace

void ExportOptions::validate() const {
  if (!mat && !hdf5) throw ParameterError("--mat/--hdf5", "nothing to write: give --mat FILE, --hdf5 FILE or both");
  if (from_s) require_finite("--from", *from_s);
  if (to_s) require_finite("--to", *to_s);
  if (from_s && to_s && !(*from_s < *to_s)) {
    throw ParameterError("--to",
                         "must be after --from (got " + std::to_string(*to_s) + " <= " + std::to_string(*from_s) + ")");
  }
  if (mat && hdf5 && fs::absolute(*mat) == fs::absolute(*hdf5)) {
    throw ParameterError("--hdf5", "the same file as --mat (" + mat->string() + ")");
  }
  try {
    validate_rig_prefix(rig);
  } catch (const ParameterError& e) {
    throw ParameterError("--rig", e.what());
  }
}

std::vector<ConfigFile> read_configs(const std::vector<fs::path>& files) {
  std::vector<ConfigFile> out;
  std::set<std::string> names;
  for (const auto& path : files) {
    std::ifstream in(path, std::ios::binary);
    if (!in || fs::is_directory(path)) throw ParameterError("--config", path.string() + ": cannot read the file");
    std::stringstream text;
    text << in.rdbuf();
    try {
      (void)YAML::Load(text.str());
    } catch (const YAML::Exception& e) {
      throw ParameterError("--config", path.string() + ": not YAML (" + e.what() + ")");
    }
    ConfigFile c{path, identifier(path.filename().string()), text.str()};
    for (int n = 2; !names.insert(c.name).second; ++n)
      c.name = identifier(path.filename().string()) + "_" + std::to_string(n);
    out.push_back(std::move(c));
  }
  return out;
}

void check_writable(const fs::path& file) {
  const fs::path folder = file.has_parent_path() ? file.parent_path() : fs::path(".");
  if (!fs::is_directory(folder))
    throw std::runtime_error(file.string() + ": cannot write: no folder " + folder.string());
  if (fs::is_directory(file)) throw std::runtime_error(file.string() + ": cannot write: it is a folder");
  if (::access(folder.c_str(), W_OK) != 0) {
    throw std::runtime_error(file.string() + ": cannot write: the folder " + folder.string() + " is not writable");
  }
  if (fs::exists(file) && ::access(file.c_str(), W_OK) != 0) {
    throw std::runtime_error(file.string() + ": cannot write: the file is not writable");
  }
}

ExportContent collect(const ExportOptions& o, std::FILE* progress) {
  const ChannelNames names(o.rig);
  const std::int64_t t0 = report::log_time_zero_utime(o.logs, names.sensor);
  std::set<std::string> candidates;  // a requested name as logged or after the prefix; resolved below
  for (const auto& c : o.channels) {
    candidates.insert(c);
    candidates.insert(names.prefix + c);
  }
  report::TableBuilder builder(
      [&](const std::string& channel) {
        return o.channels.empty() ? channel.rfind(names.prefix, 0) == 0 : candidates.count(channel) != 0;
      },
      t0, o.from_s.value_or(-1e300), o.to_s.value_or(1e300));
  Progress meter(progress, o.logs);
  std::optional<std::int64_t> first_utime, last_utime;
  const auto scans = report::for_each_event(o.logs, [&](const lcm::LogEvent& e) {
    if (!first_utime) first_utime = e.timestamp;
    last_utime = e.timestamp;
    meter.event(e);
    builder.add(e);
  });
  const auto& counts = builder.channel_counts();
  std::vector<ChannelTable> found = builder.take();

  ExportContent content;
  if (o.channels.empty()) {
    if (found.empty()) {
      throw std::runtime_error("no channel of the rig " + names.prefix + " in the log (channels: " +
                               report::channel_list(counts) + "); --rig PREFIX for another rig");
    }
    content.tables = std::move(found);
  } else {
    std::set<std::string> taken;
    for (const auto& c : o.channels) {
      const std::string channel = report::resolve_channel(c, counts, names.prefix, "--channel");
      if (!taken.insert(channel).second) continue;  // asked for twice
      for (auto& t : found) {
        if (t.channel == channel) content.tables.push_back(std::move(t));
      }
    }
  }

  content.warnings = report::describe_scan_problems(scans);
  for (const ChannelTable& t : content.tables) {
    if (t.skipped > 0) {
      content.warnings.push_back(t.channel + ": " + std::to_string(t.skipped) +
                                 " event(s) did not decode or broke the message contract; they are left out");
    }
  }
  std::vector<std::string> logs, configs, channels;
  for (const auto& l : o.logs) logs.push_back(l.string());
  for (const auto& [channel, n] : counts) channels.push_back(channel + ": " + std::to_string(n) + " events");
  content.configs = read_configs(o.configs);
  for (const auto& c : content.configs) configs.push_back(c.path.string());

  auto& run = content.run;
  run.push_back({"exported_by", std::string("hystloop-export")});
  run.push_back({"logs", joined(logs)});
  run.push_back({"rig_prefix", names.prefix});
  run.push_back({"time_zero_utime_us", t0});
  if (first_utime) run.push_back({"first_event_utime_us", *first_utime});
  if (last_utime) run.push_back({"last_event_utime_us", *last_utime});
  if (o.from_s) run.push_back({"from_s", *o.from_s});
  if (o.to_s) run.push_back({"to_s", *o.to_s});
  run.push_back({"channels", joined(channels)});
  run.push_back({"processes", processes(content.tables)});
  run.push_back({"config_files", joined(configs)});
  run.push_back({"log_warnings", joined(content.warnings)});
  return content;
}

int run_export(const ExportOptions& o, std::FILE* progress, std::FILE* out) {
  o.validate();
  (void)read_configs(o.configs);  // refused before a long log is read
  if (o.mat) check_writable(*o.mat);
  if (o.hdf5) check_writable(*o.hdf5);
  const ExportContent content = collect(o, o.quiet ? nullptr : progress);
  for (const auto& w : content.warnings) std::fprintf(stderr, "hystloop-export: warning: %s\n", w.c_str());
  // A file left half written would look like a short run: it is removed instead.
  auto write = [&](const fs::path& file, auto&& writer) {
    if (!o.quiet && progress != nullptr) std::fprintf(progress, "hystloop-export: writing %s\n", file.c_str());
    try {
      writer();
    } catch (...) {
      std::error_code ec;
      fs::remove(file, ec);
      throw;
    }
  };
  if (o.hdf5) write(*o.hdf5, [&] { write_hdf5(*o.hdf5, content); });
  if (o.mat) write(*o.mat, [&] { write_mat(*o.mat, content, o.mat_version); });
  if (!o.quiet && out != nullptr) {
    std::fprintf(out, "hystloop-export: %zu log file(s), rig %s\n", o.logs.size(), o.rig.c_str());
    for (const ChannelTable& t : content.tables) {
      std::fprintf(out, "  %-24s %-28s %zu rows from %llu events\n", t.channel.c_str(), t.type_name.c_str(), t.rows,
                   static_cast<unsigned long long>(t.events));
    }
    if (o.mat) std::fprintf(out, "  wrote %s\n", o.mat->c_str());
    if (o.hdf5) std::fprintf(out, "  wrote %s\n", o.hdf5->c_str());
  }
  return 0;
}

}  // namespace hystloop::exporter
