#include "ctl_pin_model.hpp"

#include "core/errors.hpp"
#include "hystloop/command_block_t.hpp"

namespace hystloop::ctl {

std::int8_t pin_model_mode(const std::string& name) {
  if (name == "mem") return command_block_t::MODE_MEM;
  if (name == "pi") return command_block_t::MODE_PI;
  if (name == "katalenic") return command_block_t::MODE_KATALENIC;
  if (name == "linear") return command_block_t::MODE_LINEAR;
  if (name == "auto" || name == "off") return command_block_t::MODE_OFF;
  throw ParameterError("model", "expected mem, pi, katalenic, linear or auto (got \"" + name + "\")");
}

}  // namespace hystloop::ctl
