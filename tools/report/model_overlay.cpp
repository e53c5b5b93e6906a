#include "model_overlay.hpp"

#include <cmath>
#include <limits>
#include <map>
#include <optional>

#include "core/errors.hpp"
#include "hystloop/command_block_t.hpp"
#include "models/mem.hpp"

namespace hystloop::report {

namespace {

struct PublishedSet {
  double t_s = 0.0;
  std::int32_t version = 0;
  hystloop::MemParams params;
  double residual_m = 0.0;  // of the fit it came from; 0 for a set not fitted (sent by hand)
};

std::optional<hystloop::MemParams> usable(double c1, double c2, double c3) {
  const hystloop::MemParams p{c1, c2, c3};
  try {
    p.validate();
  } catch (const ParameterError&) {
    return std::nullopt;  // a set the model refuses is drawn as no set
  }
  return p;
}

}  // namespace

std::vector<double> mem_model_y(const std::vector<TrackPoint>& ticks, const ReportMetrics& m) {
  std::vector<PublishedSet> published;  // in time order
  std::map<std::int32_t, hystloop::MemParams> by_version;
  if (m.params_initial) {
    if (const auto p = usable(m.params_initial->c1, m.params_initial->c2, m.params_initial->c3)) {
      by_version.emplace(m.params_initial->version, *p);
      published.push_back({-std::numeric_limits<double>::infinity(), m.params_initial->version, *p, 0.0});
    }
  }
  for (const auto& h : m.params_history) {
    if (!h.valid || h.model != "mem") continue;
    const auto p = usable(h.c1, h.c2, h.c3);
    if (!p) continue;
    by_version.insert_or_assign(h.version, *p);
    published.push_back({h.t_s, h.version, *p, h.residual_m});
  }
  if (published.empty()) return {};

  std::vector<double> y(ticks.size(), std::numeric_limits<double>::quiet_NaN());
  hystloop::MemModel model;
  std::optional<std::int32_t> in_use;
  double offset_m = 0.0;
  std::size_t next_published = 0;  // published[next_published - 1] is the latest at or before the tick
  for (std::size_t i = 0; i < ticks.size(); ++i) {
    const TrackPoint& p = ticks[i];
    while (next_published < published.size() && published[next_published].t_s <= p.t_s) ++next_published;
    std::int32_t version = next_published > 0 ? published[next_published - 1].version : published.front().version;
    if (p.params_version && by_version.count(*p.params_version) != 0) version = *p.params_version;
    if (p.mode == command_block_t::MODE_EXPERIMENT) {
      // The set in use during an identification experiment is the one the experiment is to
      // replace; the loop to compare it with is the one fitted from it: the first set published
      // after it that carries a fit residual (a set sent by hand, as the demo re-announces its
      // starting set, carries none).
      for (std::size_t j = next_published; j < published.size(); ++j) {
        if (published[j].residual_m > 0.0) {
          version = published[j].version;
          break;
        }
      }
    }
    const hystloop::MemParams& set = by_version.at(version);
    if (!std::isfinite(p.u_V) || !std::isfinite(p.y_m)) continue;
    if (!in_use) {
      model = hystloop::MemModel(set);
      model.reset(p.u_V);
      offset_m = p.y_m - model.output();
    } else if (*in_use != version) {
      model.set_params(set);
    }
    in_use = version;
    const std::uint64_t reversals_before = model.reversals();
    const double y_model = model.forward(p.u_V);
    // Each branch starts where the measured one does: what is compared is the shape the model
    // predicts from a reversal, not an offset that the model's open-loop run (and every swap of
    // set on the way) accumulates over a long log.
    if (model.reversals() != reversals_before) offset_m = p.y_m - y_model;
    y[i] = y_model + offset_m;
  }
  return y;
}

}  // namespace hystloop::report
