#include "model_registry.hpp"

#include <cstdio>
#include <stdexcept>
#include <type_traits>
#include <vector>

#include "models/model_descriptors.hpp"
#include "models/model_concepts.hpp"

namespace hystloop::model_tool {
namespace {

// A model with dynamics: the input is held for dt [s] (the Banning stage).
template <class M>
concept SteppedStage = requires(M& m, const M& cm, double u, double dt) {
  m.reset(u);
  { m.step(u, dt) }
  noexcept->std::same_as<double>;
  { cm.output() }
  noexcept->std::same_as<double>;
};

template <class D>
constexpr bool kHasInverse = !std::is_void_v<typename D::Inverse>;

template <class D>
class RunFor final : public ModelRun {
 public:
  using Forward = typename D::Forward;
  static_assert(HysteresisForward<Forward> || SteppedStage<Forward>);

  explicit RunFor(const typename D::Params& params) : params_(params) {}

  std::vector<double> forward(const std::vector<double>& t, const std::vector<double>& u) const override {
    std::vector<double> y(u.size());
    if (u.empty()) return y;
    Forward model(params_);
    model.reset(u.front());
    if constexpr (HysteresisForward<Forward>) {
      for (std::size_t k = 0; k < u.size(); ++k) y[k] = model.forward(u[k]);
    } else {
      // Row k: u[k] held from t[k-1] to t[k], y[k] at t[k]; the first row is the equilibrium at u[0].
      y[0] = model.output();
      for (std::size_t k = 1; k < u.size(); ++k) y[k] = model.step(u[k], t[k] - t[k - 1]);
    }
    return y;
  }

  std::vector<double> inverse([[maybe_unused]] const std::vector<double>& t,
                              [[maybe_unused]] const std::vector<double>& y_ref) const override {
    if constexpr (kHasInverse<D>) {
      using Inverse = typename D::Inverse;
      static_assert(HysteresisInverse<Inverse>);
      std::vector<double> u(y_ref.size());
      if (y_ref.empty()) return u;
      Inverse inv(params_);
      inv.reset(y_ref.front());
      for (std::size_t k = 0; k < y_ref.size(); ++k) u[k] = inv.inverse(y_ref[k]);
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
