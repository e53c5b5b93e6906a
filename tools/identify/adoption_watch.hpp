#pragma once
// hystloop-identify --publish: did the compensator adopt the set it was sent? Fed with what is
// heard on the rig after publishing, it decides from the version in use, and words the answer:
//   adopted by 'compensator' (version N)
//   not adopted within S s ('compensator' in use: version M)
//   not adopted within S s (no 'compensator' reported on HX_STATUS; heard: bridge, logger)
//   no rig is running (nothing reported on HX_STATUS within S s)
// The version in use is the compensator's own HX_STATUS counter "params_version" (the name the
// re-identifier reports it by) when its status carries one, else the params_version its
// HX_COMMAND ticks carry (every tick names the set it was planned with, as hystloop-ctl watch
// reads it). A set is swapped in only at a reversal of the stage's input: a stage at rest adopts
// nothing. When the compensator's refusal counters rise meanwhile, the answer says which.
// No LCM here: ParamsLink::wait_for_adoption listens and feeds it.

#include <cstdint>
#include <map>
#include <optional>
#include <set>
#include <string>

#include "hystloop/service_status_t.hpp"

namespace hystloop {

class AdoptionWatch {
 public:
  // axis: the axis the set is for; its params_version counter (params_version_counter) is watched.
  AdoptionWatch(std::string compensator_process, std::int32_t published_version, int axis = 0);

  void on_status(const service_status_t& status);
  void on_command_version(std::int32_t params_version);  // of a command tick

  bool adopted() const noexcept;
  // The version the compensator uses, as far as it was heard; nullopt when none was.
  std::optional<std::int64_t> version_in_use() const noexcept;
  // The answer after waiting waited_s; status_channel names the channel in it (e.g. "HX_STATUS").
  std::string verdict(double waited_s, const std::string& status_channel) const;

 private:
  std::string compensator_;
  std::int32_t version_;
  std::string counter_;          // the compensator's counter of the set in use on the axis
  std::set<std::string> heard_;  // processes that reported on HX_STATUS
  bool compensator_heard_ = false;
  std::optional<std::int64_t> status_version_;                          // the compensator's params_version counter
  std::optional<std::int64_t> command_version_;                         // the last command tick's
  std::map<std::string, std::int64_t> refusals_first_, refusals_last_;  // the compensator's refusal counters
};

}  // namespace hystloop
