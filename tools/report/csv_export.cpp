#include "csv_export.hpp"

#include <cstdio>
#include <fstream>
#include <memory>
#include <optional>
#include <sstream>
#include <stdexcept>

#include "code_legend.hpp"
#include "decode.hpp"
#include "lcm/blocks.hpp"
#include "log_reader.hpp"

namespace hystloop::report {

namespace {

using Kind = MessageKind;

std::string num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.12g", v);
  return buf;
}

std::string csv_quoted(const std::string& text) {
  std::string out = "\"";
  for (const char c : text) {
    if (c == '"') out += '"';
    out += c;
  }
  return out + '"';
}

std::string joined(const std::vector<double>& values) {
  std::string out;
  for (const double v : values) {
    if (!out.empty()) out += ' ';
    out += num(v);
  }
  return csv_quoted(out);
}

const char* header(Kind kind) {
  switch (kind) {
    case Kind::kSensor:
      return "block_utime_us,block_seq,dt_s,buffer_depth_ticks,utime_us,seq,u_V,u_ff_V,u_fb_V,y_ref_m,y_m,flags";
    case Kind::kCommand: return "block_utime_us,block_seq,sample_seq,seq,u_ff_V,y_ref_m,params_version,mode";
    case Kind::kTrajectory:
      return "utime_us,version,shape,amplitude_m,offset_m,frequency_Hz,phase_rad,start_utime_us,blend_s,n_points,"
             "points_t_s,points_y_m";
    case Kind::kParams:
      return "utime_us,version,c1_m_per_V,c2_m_per_V_pow_1_plus_c3,c3,residual_m,samples_used,window_s,valid,source";
    case Kind::kStatus:
      return "utime_us,process,host,pid,state,detail,start_utime_us,loop_p50_us,loop_p99_us,loop_max_us,"
             "latency_p50_us,latency_p99_us,latency_max_us,late,rejected,counters";
    case Kind::kControl:
      return "utime_us,request_id,command,target,mode,kp,ki_per_s,kd_s,experiment,experiment_amplitude_V,"
             "experiment_offset_V,experiment_frequency_Hz,experiment_duration_s";
    default: return "size_bytes";
  }
}

// Appends comma-separated fields to a row.
class Fields {
 public:
  explicit Fields(std::string& out) : out_(out) { out_.clear(); }
  Fields& i(long long v) { return raw(std::to_string(v)); }
  Fields& d(double v) { return raw(num(v)); }
  Fields& s(const std::string& text) { return raw(csv_quoted(text)); }
  Fields& raw(const std::string& text) {
    if (!first_) out_ += ',';
    first_ = false;
    out_ += text;
    return *this;
  }

 private:
  std::string& out_;
  bool first_ = true;
};

// The rows of one event: emit(t_s, fields) for each, fields after "t_s,recv_utime_us,"; false
// (and no row) if the event does not decode. One row per event, or per tick for the blocks of
// HX_SENSOR (each tick dated as the report's time axis dates it) and HX_COMMAND (the event's time).
class RowDecoder {
 public:
  template <class Emit>
  bool rows(Kind kind, const lcm::LogEvent& e, std::int64_t t0_utime, std::string& out, Emit&& emit) {
    auto t_of = [t0_utime](std::int64_t utime) { return static_cast<double>(utime - t0_utime) * 1e-6; };
    switch (kind) {
      case Kind::kSensor: {
        const auto& m = sensor_;
        if (!decode_checked(e, sensor_)) return false;
        std::size_t i = 0;
        for_each_tick(m, [&](const SensorTick& k) {
          const double t = t_of(tick_recv_utime(e.timestamp, m.n_ticks, i++, m.dt_s));
          Fields(out)
              .i(m.utime)
              .i(m.seq)
              .d(m.dt_s)
              .i(m.buffer_depth_ticks)
              .i(k.utime)
              .i(k.seq)
              .d(k.u_V)
              .d(k.u_ff_V)
              .d(k.u_fb_V)
              .d(k.y_ref_m)
              .d(k.y_m)
              .i(k.flags);
          emit(t, out);
        });
        return true;
      }
      case Kind::kCommand: {
        const auto& m = command_;
        if (!decode_checked(e, command_)) return false;
        for_each_tick(m, [&](const CommandTick& k) {
          Fields(out)
              .i(m.utime)
              .i(m.seq)
              .i(m.sample_seq)
              .i(k.seq)
              .d(k.u_ff_V)
              .d(k.y_ref_m)
              .i(k.params_version)
              .i(k.mode);
          emit(t_of(e.timestamp), out);
        });
        return true;
      }
      default:
        if (!row(kind, e, out)) return false;
        emit(t_of(e.timestamp), out);
        return true;
    }
  }

 private:
  bool row(Kind kind, const lcm::LogEvent& e, std::string& out) {
    switch (kind) {
      case Kind::kTrajectory: {
        const auto& m = trajectory_;
        if (!decode_checked(e, trajectory_)) return false;
        Fields(out)
            .i(m.utime)
            .i(m.version)
            .i(m.shape)
            .d(m.amplitude_m)
            .d(m.offset_m)
            .d(m.frequency_Hz)
            .d(m.phase_rad)
            .i(m.start_utime)
            .d(m.blend_s)
            .i(m.n_points)
            .raw(joined(m.points_t_s))
            .raw(joined(m.points_y_m));
        return true;
      }
      case Kind::kParams: {
        const auto& m = params_;
        if (!decode_checked(e, params_)) return false;
        Fields(out)
            .i(m.utime)
            .i(m.version)
            .d(m.c1)
            .d(m.c2)
            .d(m.c3)
            .d(m.residual_m)
            .i(m.samples_used)
            .d(m.window_s)
            .i(m.valid ? 1 : 0)
            .s(m.source);
        return true;
      }
      case Kind::kStatus: {
        const auto& m = status_;
        if (!decode_checked(e, status_)) return false;
        std::string counters;
        for (std::size_t k = 0; k < m.counter_names.size(); ++k) {
          if (k > 0) counters += ';';
          counters += m.counter_names[k];
          counters += '=';
          counters += std::to_string(m.counter_values[k]);
        }
        Fields(out)
            .i(m.utime)
            .s(m.process)
            .s(m.host)
            .i(m.pid)
            .i(m.state)
            .s(m.detail)
            .i(m.start_utime)
            .d(m.loop_p50_us)
            .d(m.loop_p99_us)
            .d(m.loop_max_us)
            .d(m.latency_p50_us)
            .d(m.latency_p99_us)
            .d(m.latency_max_us)
            .i(m.late)
            .i(m.rejected)
            .s(counters);
        return true;
      }
      case Kind::kControl: {
        const auto& m = control_;
        if (!decode_checked(e, control_)) return false;
        Fields(out)
            .i(m.utime)
            .i(m.request_id)
            .i(m.command)
            .s(m.target)
            .i(m.mode)
            .d(m.kp)
            .d(m.ki)
            .d(m.kd)
            .s(m.experiment)
            .d(m.experiment_amplitude_V)
            .d(m.experiment_offset_V)
            .d(m.experiment_frequency_Hz)
            .d(m.experiment_duration_s);
        return true;
      }
      default: Fields(out).i(e.datalen); return true;
    }
  }

 private:
  sensor_block_t sensor_;
  command_block_t command_;
  trajectory_t trajectory_;
  mem_params_t params_;
  service_status_t status_;
  control_t control_;
};

struct ChannelWriter {
  CsvExport result;
  std::optional<Kind> kind;  // decided by the first event
  std::ofstream out;
};

std::string safe_file_name(std::string name) {
  for (char& c : name) {
    const bool ok =
        (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_' || c == '.' || c == '-';
    if (!ok) c = '_';
  }
  return name;
}

void write_legend(const CsvExport& result, const std::string& csv_header) {
  std::ofstream out(result.legend_file);
  out << csv_legend_text(result.channel, result.type_name, csv_header);
  out.close();
  if (!out) throw std::runtime_error(result.legend_file.string() + ": cannot write");
}

}  // namespace

std::filesystem::path csv_path(const std::filesystem::path& dir, const std::string& channel) {
  return dir / (safe_file_name(channel) + ".csv");
}

std::filesystem::path csv_legend_path(const std::filesystem::path& dir, const std::string& channel) {
  return dir / (safe_file_name(channel) + ".legend.txt");
}

std::string csv_legend_text(const std::string& channel, const std::string& type_name, const std::string& csv_header) {
  std::string out = "# Integer codes of the columns of " + csv_path("", channel).string() + " (" + type_name +
                    "), from the constants of lcmtypes/*.lcm\n";
  std::istringstream columns(csv_header);
  std::string column;
  bool any = false;
  while (std::getline(columns, column, ',')) {
    if (const CodeLegend* legend = find_code_legend(type_name, column)) {
      out += column + ": " + legend->text() + '\n';
      any = true;
    } else if (type_name == "hystloop.mem_params_t" && column == "valid") {
      out += "valid: 0=false,1=true\n";  // a boolean of the message, written as 0/1
      any = true;
    }
  }
  if (!any) out += "# no column of this channel is integer-coded\n";
  return out;
}

std::vector<CsvExport> export_csv(const std::vector<std::filesystem::path>& logs,
                                  const std::vector<std::string>& channels, std::int64_t t0_utime, double lower_s,
                                  double upper_s, const std::filesystem::path& dir) {
  std::vector<std::unique_ptr<ChannelWriter>> writers;
  for (const auto& channel : channels) {
    auto writer = std::make_unique<ChannelWriter>();
    writer->result.channel = channel;
    writer->result.file = csv_path(dir, channel);
    writer->result.legend_file = csv_legend_path(dir, channel);
    writer->out.open(writer->result.file);
    if (!writer->out) throw std::runtime_error(writer->result.file.string() + ": cannot write");
    writers.push_back(std::move(writer));
  }
  RowDecoder decoder;
  std::string row;
  for_each_event(logs, [&](const lcm::LogEvent& e) {
    for (auto& w : writers) {
      if (e.channel != w->result.channel) continue;
      if (!w->kind) {  // the first event decides the channel's type and header
        w->kind = message_kind(e);
        w->result.type_name = lcm_type_name(*w->kind);
        w->out << "t_s,recv_utime_us," << header(*w->kind) << '\n';
      }
      const bool decoded = decoder.rows(*w->kind, e, t0_utime, row, [&](double row_t, const std::string& fields) {
        if (row_t < lower_s || row_t > upper_s) return;
        w->out << num(row_t) << ',' << e.timestamp << ',' << fields << '\n';
        ++w->result.rows;
      });
      if (!decoded) ++w->result.skipped;
    }
  });
  std::vector<CsvExport> results;
  for (auto& w : writers) {
    if (!w->kind) {  // no event at all
      w->out << "t_s,recv_utime_us\n";
      w->result.type_name = lcm_type_name(Kind::kUnknown);
    }
    w->out.close();
    if (!w->out) throw std::runtime_error(w->result.file.string() + ": write failed");
    write_legend(w->result, w->kind ? header(*w->kind) : std::string());
    results.push_back(w->result);
  }
  return results;
}

}  // namespace hystloop::report
