#pragma once
// True in the sanitizer job's build (the debug preset: -O0 with AddressSanitizer,
// docs/reliability.md "Sanitizers and long-run memory"), where suites skip or shorten the cases
// that take minutes; the release suite runs them in full.
namespace stokesian::test {
#if defined(__SANITIZE_ADDRESS__)
inline constexpr bool kSanitized = true;
#else
inline constexpr bool kSanitized = false;
#endif
}  // namespace stokesian::test
