#pragma once
// Sanitizer builds (Debug + ASan) run the same checks on fewer cases to stay within a few seconds:
// a test picks its case count from kSanitized.

namespace hystloop::testing {

#if defined(__SANITIZE_ADDRESS__)
inline constexpr bool kSanitized = true;
#else
inline constexpr bool kSanitized = false;
#endif

}  // namespace hystloop::testing
