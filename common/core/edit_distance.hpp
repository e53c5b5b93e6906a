#pragma once
// How many edits turn a into b, for "did you mean" suggestions (config keys, --param names): an
// edit inserts, deletes or substitutes a character, or swaps two neighbours ("gian" is one edit
// from "gain"; the optimal-string-alignment distance). Case-sensitive: callers lower-case first
// where case does not matter.

#include <cstddef>
#include <string_view>

namespace hystloop {

std::size_t edit_distance(std::string_view a, std::string_view b);

}  // namespace hystloop
