#include "identify_output.hpp"

#include <fstream>
#include <iostream>
#include <stdexcept>
#include <system_error>

namespace hystloop {

namespace fs = std::filesystem;

OutputTarget output_target(const std::string& out) {
  OutputTarget t;
  if (out.empty()) return t;
  std::error_code ec;
  if (out.back() == '/' || fs::is_directory(out, ec)) {
    t.plots_dir = fs::path(out);
    t.yaml = (fs::path(out) / "config.yaml").string();
  } else {
    t.yaml = out;
  }
  return t;
}

int write_yaml(const OutputTarget& target, const std::string& yaml) {
  std::cout << "--- YAML\n" << yaml;
  if (target.yaml.empty()) return 0;
  if (target.plots_dir) {
    std::error_code ec;
    fs::create_directories(*target.plots_dir, ec);
    if (ec) {
      std::cerr << "hystloop-identify: --out " << target.plots_dir->string() << ": cannot make the folder ("
                << ec.message() << ")\n";
      return 2;
    }
  }
  std::ofstream f(target.yaml);
  f << "# written by hystloop-identify\n" << yaml;
  if (!f) {
    std::cerr << "hystloop-identify: cannot write " << target.yaml << "\n";
    return 2;
  }
  std::cout << "written to " << target.yaml << "\n";
  return 0;
}

int write_plots(const OutputTarget& target, const SampleTable& record, const FitPlotInput& input,
                const std::string& gnuplot) {
  if (!target.plots_dir) return 0;
  try {
    FitPlotOptions o;
    o.gnuplot = gnuplot;
    const FitPlotFiles files = write_fit_plots(record, input, *target.plots_dir, o);
    std::cout << "plots: " << files.data_files.size() << " data file(s) and " << files.script.filename().string();
    if (!files.images.empty()) {
      std::cout << ", " << files.images.size() << " image(s) (" << files.terminal << "):";
      for (const auto& i : files.images) std::cout << " " << i.filename().string();
    }
    std::cout << " in " << target.plots_dir->string() << "\n";
    if (!files.warning.empty()) std::cerr << "hystloop-identify: warning: " << files.warning << "\n";
  } catch (const std::runtime_error& e) {
    std::cerr << "hystloop-identify: plots: " << e.what() << "\n";
    return 2;
  }
  return 0;
}

}  // namespace hystloop
