#include "runtime/summary_file.hpp"

#include <cmath>
#include <exception>
#include <fstream>
#include <stdexcept>
#include <system_error>

#include <spdlog/spdlog.h>

namespace hystloop {

std::string to_json_text(const nlohmann::ordered_json& value) {
  return value.dump(2, ' ', true, nlohmann::ordered_json::error_handler_t::replace) + "\n";
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

void write_summary_file(const std::filesystem::path& path, const nlohmann::ordered_json& value) noexcept {
  try {
    write_file_atomically(path, to_json_text(value));
  } catch (const std::exception& e) {
    spdlog::error("could not write the summary: {}", e.what());
  }
}

nlohmann::ordered_json latency_summary_us(const LatencyStats& stats) {
  const bool timed = stats.count() > 0;
  const auto us = [&](double ns) { return timed ? std::round(ns / 100.0) / 10.0 : -1.0; };
  return {{"p50", us(timed ? stats.percentile(0.5) : 0.0)},
          {"p99", us(timed ? stats.percentile(0.99) : 0.0)},
          {"max", us(timed ? static_cast<double>(stats.max_ns()) : 0.0)},
          {"count", stats.count()}};
}

}  // namespace hystloop
