#pragma once
// hystloop-identify --publish: a fitted set sent to a running compensator, which swaps it in at
// its next reversal: a MEM set on the rig's HX_PARAMS as mem_params_t (the MEM inverse's
// parameters; the mode stays), any model on HX_MODEL as model_params_t (the feedforward switches
// to it). On a keyed rig both are signed (the process's rig auth, lcm/rig_auth.hpp). Then,
// unless told not to wait, it listens for whether the compensator adopted it (adoption_watch.hpp). Each run publishes
// with its own publisher_id (process_publisher_id()): the compensator orders versions per publisher, so a new run is
// never refused as stale, whatever versions others sent. The link is opened before the fit, so a refused URL or a
// missing multicast route fails fast; the version is looked up after the fit, so it is fresh.

#include <chrono>
#include <cstddef>
#include <limits>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include <lcm/lcm-cpp.hpp>

#include "hystloop/mem_params_t.hpp"
#include "hystloop/model_params_t.hpp"
#include "ident/mem_fit.hpp"
#include "lcm/channels.hpp"
#include "models/model_set.hpp"

namespace hystloop {

struct PublishOptions {
  std::string lcm_url;         // empty: $LCM_DEFAULT_URL, else the ttl=0 default
  bool allow_network = false;  // needed for a URL whose packets leave the host
  std::string rig = std::string(kDefaultRigPrefix);
  std::optional<std::int32_t> version;  // empty: next_params_version(highest heard)
  double listen_s = 0.5;                // how long to listen for the version in use [s]
  int repeats = 3;                      // UDP may drop one; receivers dedupe by version
  std::chrono::milliseconds gap{10};
  std::string compensator = "compensator";  // the process whose adoption counts
  int axis = 0;                             // the axis the set is for (0: x): its messages name it
  double timeout_s = 5.0;                   // how long to wait for it [s]

  // Throws ParameterError naming the field ("version", "listen_s", "repeats", "rig.prefix",
  // "timeout", "compensator").
  void validate() const;
};

// 1 + the highest version heard, and at least 2: version 1 is what a compensator starts with
// from its configuration, so a first published set must supersede it.
std::int32_t next_params_version(std::int32_t highest_heard) noexcept;

// The message for a successful fit. residual_m is the fit's own residual (integrated
// branches), samples_used the fit's, window_s the time span of the samples given to it.
mem_params_t to_mem_params(const MemFitResult& fit, double window_s, std::int32_t version, std::int64_t utime_us,
                           const std::string& source);

// The figures of a fit that travel with its set.
struct FitFigures {
  double residual_m = 0.0;                                          // RMS on the data fitted [m]
  double heldout_rms_m = std::numeric_limits<double>::quiet_NaN();  // NaN: not ranked
  std::size_t samples_used = 0;
  double window_s = 0.0;  // time span of the samples given to the fit [s]
};

// The HX_MODEL message for any fitted model: its kind and parameters, the stage left as the
// receiver has it (a hysteresis fit says nothing of the stage), valid = true.
model_params_t to_model_params(const ModelParamSet& set, const FitFigures& fit, std::int32_t version,
                               std::int64_t utime_us, const std::string& source);

// "hystloop-identify@<host>".
std::string identify_source();

class ParamsLink {
 public:
  // Throws ParameterError for a refused URL or rig prefix, std::runtime_error if LCM cannot start.
  explicit ParamsLink(const PublishOptions& options);

  // Listens options.listen_s on HX_PARAMS (and the params_version of HX_COMMAND's ticks: a
  // compensator does not repeat the set it uses) and returns the highest version heard, 0 if none.
  std::int32_t highest_version_heard();

  // Publishes msg options.repeats times, options.gap apart (on HX_PARAMS / HX_MODEL). Returns
  // how many were handed to LCM (0 if the message fails the contract check).
  // Each with its axis set to options.axis.
  int publish(mem_params_t msg);
  int publish(model_params_t msg);

  struct Adoption {
    bool adopted = false;
    std::string verdict;  // AdoptionWatch::verdict
  };
  // Listens on HX_STATUS and HX_COMMAND until options.compensator uses `version`, at most
  // options.timeout_s.
  Adoption wait_for_adoption(std::int32_t version);

  const std::string& url() const noexcept { return url_; }
  const ChannelNames& channels() const noexcept { return channels_; }

 private:
  PublishOptions options_;
  ChannelNames channels_;
  std::string url_;
  std::unique_ptr<lcm::LCM> lcm_;
};

}  // namespace hystloop
