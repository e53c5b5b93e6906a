#include "model_registry.hpp"

#include <cstdio>
#include <stdexcept>
#include <vector>

#include "models/model_descriptors.hpp"
#include "models/model_concepts.hpp"
#include "model_loop.hpp"

namespace hystloop::model_tool {
namespace {

template <class D>
class RunFor final : public ModelRun {
 public:
  explicit RunFor(const typename D::Params& params) : params_(params) {}

  std::vector<double> forward(const std::vector<double>& t, const std::vector<double>& u) const override {
    std::vector<double> y(u.size());
    run_forward<D>(params_, t, u, y);
    return y;
  }

  std::vector<double> inverse([[maybe_unused]] const std::vector<double>& t,
                              [[maybe_unused]] const std::vector<double>& y_ref) const override {
    if constexpr (kHasInverse<D>) {
      std::vector<double> u(y_ref.size());
      run_inverse<D>(params_, y_ref, u);
      return u;
    } else {
      throw std::logic_error(std::string(D::name) + " has no inverse");
    }
  }

 private:
  typename D::Params params_;
};

template <class D>
const ModelEntry kEntry{D::name,
                        D::summary,
                        D::notes,
                        kHasInverse<D>,
                        !HysteresisForward<typename D::Forward>,
                        [] { return describe(D::table()); },
                        [](const std::vector<Assignment>& assignments) -> std::unique_ptr<ModelRun> {
                          return std::make_unique<RunFor<D>>(params_from<D>(assignments));
                        }};
const std::vector<const ModelEntry*> kRegistry = [] {
  std::vector<const ModelEntry*> entries;
  AllModels::for_each([&]<class D>() { entries.push_back(&kEntry<D>); });
  return entries;
}();

}  // namespace

std::span<const ModelEntry* const> model_registry() { return kRegistry; }

const ModelEntry* find_model(std::string_view name) {
  for (const ModelEntry* m : kRegistry) {
    if (m->name == name) return m;
  }
  return nullptr;
}

std::string model_names(std::string_view separator) {
  std::string out;
  for (const ModelEntry* m : kRegistry) {
    if (!out.empty()) out += separator;
    out += m->name;
  }
  return out;
}

std::string invertible_model_names(std::string_view separator) {
  std::string out;
  for (const ModelEntry* m : kRegistry) {
    if (!m->has_inverse) continue;
    if (!out.empty()) out += separator;
    out += m->name;
  }
  return out;
}

std::string models_help() {
  std::string out =
      "Models and their parameters (--param NAME=VALUE, repeatable; SI units, 'x' = the Katalenic operator's units):\n";
  char line[512];
  for (const ModelEntry* m : kRegistry) {
    out += "\n  " + std::string(m->name) + ": " + std::string(m->summary) + "\n";
    if (!m->notes.empty()) out += "    (" + std::string(m->notes) + ")\n";
    for (const ParamInfo& p : m->parameters()) {
      const std::string name = p.alias.empty() ? p.name : p.name + " (or " + p.alias + ")";
      const std::string unit = "[" + p.unit + "]";
      std::snprintf(line, sizeof line, "    %-28s %-12s default %-22s %s", name.c_str(), unit.c_str(),
                    p.default_text.c_str(), p.description.c_str());
      out += line;
      if (p.kind == "list")
        out += " (comma-separated list)";
      else if (p.kind == "integer")
        out += " (integer)";
      else if (p.kind != "number")
        out += " (one of " + p.kind + ")";
      out += "\n";
    }
  }
  return out;
}

}  // namespace hystloop::model_tool
