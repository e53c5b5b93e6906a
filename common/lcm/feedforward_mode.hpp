#pragma once
// command_block_t.mode / control_t.mode <-> FeedforwardMode. The wire's MODE_* constants are the
// enum's numbers; this is the one place that says so, and the compiler checks it.

#include <cstdint>
#include <optional>

#include "hystloop/command_block_t.hpp"
#include "models/feedforward_mode.hpp"

namespace hystloop {

static_assert(command_block_t::MODE_OFF == static_cast<std::int8_t>(FeedforwardMode::kOff));
static_assert(command_block_t::MODE_LINEAR == static_cast<std::int8_t>(FeedforwardMode::kLinear));
static_assert(command_block_t::MODE_MEM == static_cast<std::int8_t>(FeedforwardMode::kMem));
static_assert(command_block_t::MODE_PI == static_cast<std::int8_t>(FeedforwardMode::kPi));
static_assert(command_block_t::MODE_KATALENIC == static_cast<std::int8_t>(FeedforwardMode::kKatalenic));
static_assert(command_block_t::MODE_EXPERIMENT == static_cast<std::int8_t>(FeedforwardMode::kExperiment));

// Any MODE_* (MODE_EXPERIMENT too: whether a mode is selectable is the caller's question); empty
// for a number that names none.
inline std::optional<FeedforwardMode> feedforward_mode_from_wire(std::int8_t mode) noexcept {
  const auto m = static_cast<FeedforwardMode>(mode);
  if (m == FeedforwardMode::kOff || m == FeedforwardMode::kExperiment || model_kind_of(m)) return m;
  return std::nullopt;
}

inline std::int8_t to_wire(FeedforwardMode mode) noexcept { return static_cast<std::int8_t>(mode); }

}  // namespace hystloop
