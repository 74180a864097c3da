#pragma once
// Run-time instruction-set choice of the vectorised kernels (ewald/spread_fast.cpp,
// engine/kernels/direct_fast.cpp): each kernel is compiled twice, once with STOKESIAN_AVX2_FMA
// (AVX2 + FMA) and once for the baseline ISA, and calls the first when the CPU has both.
#if defined(__x86_64__) && defined(__GNUC__)
#define STOKESIAN_AVX2_FMA __attribute__((target("avx2,fma")))
#else
#define STOKESIAN_AVX2_FMA
#endif

namespace stokesian {

// Whether this CPU runs the STOKESIAN_AVX2_FMA builds (checked once).
inline bool cpu_has_avx2_fma() {
#if defined(__x86_64__) && defined(__GNUC__)
  static const bool yes = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
  return yes;
#else
  return false;
#endif
}

}  // namespace stokesian
