#pragma once
// Text checks the tests share: whether a message (a refusal, a log, a tool's output) says a part.

#include <string>
#include <string_view>

namespace hystloop::testing {

inline bool contains(std::string_view text, std::string_view part) { return text.find(part) != std::string_view::npos; }

}  // namespace hystloop::testing
