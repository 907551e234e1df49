// Whether this test binary was built with AddressSanitizer (CI's ASan+UBSan stage, `./irdist test
// --sanitize`), where the estimator runs 10-30x slower. A test that repeats one code path on many
// inputs may run fewer of them there: every code path still runs under the sanitizers, and the
// Release suite asserts the figures on all of them.
#pragma once

namespace irdist::testing {

#if defined(__SANITIZE_ADDRESS__)
inline constexpr bool kSanitizedBuild = true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
inline constexpr bool kSanitizedBuild = true;
#else
inline constexpr bool kSanitizedBuild = false;
#endif
#else
inline constexpr bool kSanitizedBuild = false;
#endif

}  // namespace irdist::testing
