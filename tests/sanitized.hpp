#pragma once
/// Whether this test binary was built with a sanitizer (ASan, TSan; GCC and Clang spell the
/// check differently). A step there costs 10–60× more, so the heaviest tests run a smaller
/// cut of their scene: the same code paths (contacts, colours, threads), fewer bodies.
#include <cstddef>

namespace tumble::testing {

#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
inline constexpr bool kSanitized = true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer)
inline constexpr bool kSanitized = true;
#else
inline constexpr bool kSanitized = false;
#endif
#else
inline constexpr bool kSanitized = false;
#endif

/// Bodies of the `pile` scene a test steps: all 1,000, or the first 300 (three layers that
/// land on one another: ~300 contacts in 20+ colours by step 45) in a sanitizer build.
inline constexpr std::size_t kPileBodies = kSanitized ? 300 : 1000;

}  // namespace tumble::testing
