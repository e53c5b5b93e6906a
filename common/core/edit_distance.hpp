#pragma once
// How many edits turn a into b, for "did you mean" suggestions (config keys, --param names): an
// edit inserts, deletes or substitutes a character, or swaps two neighbours ("gian" is one edit
// from "gain"; the optimal-string-alignment distance). Case-sensitive: callers lower-case first
// where case does not matter, with ascii_lower.

#include <cstddef>
#include <string>
#include <string_view>

namespace hystloop {

std::size_t edit_distance(std::string_view a, std::string_view b);

// s with A-Z as a-z (names, keys and levels are ASCII; no locale is consulted).
std::string ascii_lower(std::string_view s);

}  // namespace hystloop
