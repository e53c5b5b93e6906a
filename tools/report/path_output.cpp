#include "path_output.hpp"

#include <cmath>
#include <cstdio>
#include <sstream>

#include "core/errors.hpp"
#include "models/axis_coupling.hpp"

namespace hystloop::report {

namespace {

using Json = nlohmann::ordered_json;  // keys in the order written

// A mismatch of the logged y_ref and the path found above this means the path was not found
// exactly (found, it is a few 1e-22 m of rounding).
constexpr double kReferenceToleranceM = 1e-12;

Json num(const std::optional<double>& v) { return v && std::isfinite(*v) ? Json(*v) : Json(nullptr); }

std::string nm(const std::optional<double>& m, const char* format = "%.3f") {
  if (!m) return "—";
  char buf[32];
  std::snprintf(buf, sizeof buf, format, *m * 1e9);
  return buf;
}

// Markdown cells must not contain '|' or line breaks.
std::string cell(std::string text) {
  for (char& c : text) {
    if (c == '|' || c == '\n') c = '/';
  }
  return text;
}

std::string csv_quoted(const std::string& text) {
  std::string out = "\"";
  for (const char c : text) {
    if (c == '"') out += '"';
    out += c;
  }
  return out + '"';
}

std::string csv_number(const std::optional<double>& v) { return v ? number_text(*v, 12) : std::string(); }

std::string axis_text(const PathAxisFigures& a) { return std::string(axis_name(a.axis)) + " (" + a.role + ")"; }

double corner_s(const PathFigures& f) { return f.raster() ? f.raster()->corner_s : std::nan(""); }

// The error maps' file stem: error_map_<axis>, with the version when the log has several rasters.
std::string map_stem(const PathFigures& f, int axis, bool several) {
  std::string stem = "error_map_";
  if (several) stem.append("v").append(std::to_string(f.path.version)).append("_");
  return stem.append(axis_name(axis));
}

std::size_t measured_rasters(const std::vector<PathFigures>& paths) {
  std::size_t n = 0;
  for (const auto& f : paths) n += f.measured() && f.raster() && !f.t_s.empty() ? 1 : 0;
  return n;
}

}  // namespace

std::string path_table(const std::vector<PathFigures>& paths) {
  std::ostringstream md;
  md << "| path | axis | position | ticks | RMS [nm] | max [nm] | max abs(y_ref - r) [nm] |\n"
     << "| --- | --- | --- | ---: | ---: | ---: | ---: |\n";
  for (const auto& f : paths) {
    if (!f.measured()) {
      md << "| " << cell(f.label()) << " | — | — | — | — | — | — | not measured: " << cell(f.skipped) << " |\n";
      continue;
    }
    for (const auto& a : f.per_axis) {
      md << "| " << cell(f.label()) << " | " << axis_text(a) << " | "
         << (f.position == PositionSource::kTrue ? "true" : "measured") << " | " << a.ticks << " | " << nm(a.rms_m)
         << " | " << nm(a.max_abs_m) << " | " << nm(a.reference_mismatch_m, "%.2g") << " |\n";
    }
  }
  md << "\nr = the path's own reference of each axis at loop time seq * dt; position: the simulated stage's "
        "true position (HX_SIM_TRUTH) when the log has it, else the measured y_m; a raster over its lines "
        "(corners included, not the settle), a Lissajous figure over its duration.\n";
  for (const auto& f : paths) {
    if (!f.measured()) continue;
    char line[320];
    std::snprintf(line, sizeof line, "%s: loop time %.6f s to %.6f s (printed %.4f s)", f.label().c_str(), f.from_s,
                  f.to_s, f.printed_start_s.value_or(std::nan("")));
    md << "  " << line;
    if (f.raster()) md << ", corners " << number_text(corner_s(f) * 1e3, 5) << " ms (" << f.corner_source << ")";
    md << ", " << f.expected_ticks << " ticks (" << f.missing_ticks << " missing, " << f.safe_ticks << " safe)"
       << (f.interrupted ? ", interrupted by another trajectory" : "") << "\n";
  }
  return md.str();
}

std::string path_csv(const std::vector<PathFigures>& paths) {
  std::ostringstream out;
  out << "version,path,axis,role,position,from_s,to_s,corner_s,corner_source,ticks,expected_ticks,missing_ticks,"
         "safe_ticks,interrupted,rms_m,max_abs_m,reference_ticks,reference_mismatch_m,note\n";
  for (const auto& f : paths) {
    const std::string head = std::to_string(f.path.version) + "," + (f.raster() ? "raster" : "lissajous") + ",";
    if (!f.measured()) {
      out << head << ",,,,,,,,,,,,,,,," << csv_quoted("not measured: " + f.skipped) << "\n";
      continue;
    }
    for (const auto& a : f.per_axis) {
      out << head << axis_name(a.axis) << "," << a.role << ","
          << (f.position == PositionSource::kTrue ? "true" : "measured") << "," << number_text(f.from_s, 12) << ","
          << number_text(f.to_s, 12) << "," << (f.raster() ? number_text(corner_s(f), 12) : std::string()) << ","
          << csv_quoted(f.corner_source) << "," << a.ticks << "," << f.expected_ticks << "," << f.missing_ticks << ","
          << f.safe_ticks << "," << (f.interrupted ? 1 : 0) << "," << csv_number(a.rms_m) << ","
          << csv_number(a.max_abs_m) << "," << a.reference_ticks << "," << csv_number(a.reference_mismatch_m) << ",\n";
    }
  }
  return out.str();
}

Json paths_json(const std::vector<PathFigures>& paths) {
  Json out = Json::array();
  for (const auto& f : paths) {
    Json j{{"version", f.path.version},
           {"path", f.raster() ? "raster" : "lissajous"},
           {"label", f.label()},
           {"sent_s", f.sent_s},
           {"verdict", to_string(f.verdict)},
           {"verdict_detail", f.verdict_text},
           {"measured", f.measured()},
           {"not_measured_because", f.skipped}};
    if (f.measured()) {
      j["position"] = f.position == PositionSource::kTrue ? "true" : "measured";
      j["printed_start_s"] = num(f.printed_start_s);
      j["from_s"] = f.from_s;
      j["to_s"] = f.to_s;
      j["corner_s"] = f.raster() ? Json(corner_s(f)) : Json(nullptr);
      j["corner_source"] = f.corner_source;
      j["expected_ticks"] = f.expected_ticks;
      j["missing_ticks"] = f.missing_ticks;
      j["safe_ticks"] = f.safe_ticks;
      j["interrupted"] = f.interrupted;
      Json axes = Json::array();
      for (const auto& a : f.per_axis) {
        axes.push_back(Json{{"axis", axis_name(a.axis)},
                            {"role", a.role},
                            {"ticks", a.ticks},
                            {"rms_error_m", num(a.rms_m)},
                            {"max_abs_error_m", num(a.max_abs_m)},
                            {"reference_ticks", a.reference_ticks},
                            {"reference_mismatch_m", num(a.reference_mismatch_m)}});
      }
      j["axes"] = std::move(axes);
    }
    out.push_back(std::move(j));
  }
  return out;
}

std::vector<std::string> path_warnings(const std::vector<PathFigures>& paths) {
  std::vector<std::string> out;
  for (const auto& f : paths) {
    if (!f.measured()) continue;
    const std::string name = "scan path v" + std::to_string(f.path.version);
    if (f.missing_ticks > 0) {
      out.push_back(name + ": " + std::to_string(f.missing_ticks) + " of its " + std::to_string(f.expected_ticks) +
                    " ticks are not in the log" +
                    (f.position == PositionSource::kTrue ? " or have no true position" : "") + "; left out");
    }
    if (f.interrupted) out.push_back(name + ": another trajectory took over before its end; measured until then");
    for (const auto& a : f.per_axis) {
      if (a.reference_mismatch_m && *a.reference_mismatch_m > kReferenceToleranceM) {
        out.push_back(name + ": the logged y_ref of " + std::string(axis_name(a.axis)) +
                      " differs from the path's reference by up to " + nm(a.reference_mismatch_m, "%.3g") +
                      " nm (the path's start or corners were not found exactly, or y_ref is not the path's)");
      }
    }
  }
  return out;
}

PlotResult write_path_maps(const std::vector<PathFigures>& paths, const std::filesystem::path& dir,
                           const ErrorMapOptions& map_options, const PlotOptions& plots) {
  PlotResult out;
  const bool several = measured_rasters(paths) > 1;
  for (const auto& f : paths) {
    const RasterSpec* raster = f.raster();
    if (!f.measured() || raster == nullptr || f.t_s.empty()) continue;
    for (const auto& a : f.per_axis) {
      const auto axis = static_cast<std::size_t>(a.axis);
      const ErrorMap map = build_error_map(*raster, f.t_s, f.error_m[axis], map_options);
      // Short: write_error_map adds the RMS figures after it.
      std::string title(axis_name(a.axis));
      title.append(" (").append(a.role).append(f.position == PositionSource::kTrue ? "), true position"
                                                                                   : "), measured");
      if (several) title.append(", v").append(std::to_string(f.path.version));
      PlotResult one = write_error_map(map, dir, map_stem(f, a.axis, several), title, plots);
      out.data_files.insert(out.data_files.end(), one.data_files.begin(), one.data_files.end());
      out.images.insert(out.images.end(), one.images.begin(), one.images.end());
      if (out.warning.empty()) out.warning = one.warning;
      out.terminal = one.terminal;
    }
  }
  return out;
}

}  // namespace hystloop::report
