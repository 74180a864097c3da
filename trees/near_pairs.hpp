#pragma once
// Exact near pairs of the octree far field (trees/tree_mobility.cpp, fmm path).
//
// Mathematics: the Rotne-Prager-Yamakawa blocks of two separated spheres (r >= a_i + a_j), the
// closed forms of engine/kernels/mobility_pair.cpp (separated_scalars; docs/mobility.md). With
// d = x_i - x_j, u = 1/r, c = (a_i^2 + a_j^2)/3 and k = 1/(8 pi mu), for F and FT
//   U_i += k [u (1 + c u^2) F + u^3 (1 - 3 c u^2) (d.F) d + u^3 T x d],
//   W_i += k [u^3 F x d - u^3/2 T + 3/2 u^5 (d.T) d],
// and for FTS every block of mobility::apply_pair written out with its separated scalars.
// Overlapping and nested pairs (rare) go through mobility::pair_scalars.
//
// Sources are in tree order as separate coordinate arrays. The loop takes four sources at a time
// on 4-wide vectors (GCC vector extensions) and the remainder one by one, with the same kernel
// body; near_pairs.cpp is compiled with -fno-math-errno (so that the square roots vectorise) and
// -fno-trapping-math (CMakeLists.txt). Results differ from the plain kernel by rounding only
// (tests/test_tree_mobility.cpp compares with the direct product) and are the same on any thread
// count.
#include "trees/tree_mobility.hpp"

namespace stokesian::trees {

// The hot loops (near pairs, conversions, shifts) are also compiled for x86-64-v3 (AVX2, FMA) and
// the version is chosen at run time (GCC function multiversioning); elsewhere one portable version.
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__) && !defined(__SANITIZE_ADDRESS__)
#define STOKESIAN_TREE_CLONES __attribute__((target_clones("arch=x86-64-v3", "default")))
#else
#define STOKESIAN_TREE_CLONES
#endif

// y_i += the exact mobility blocks (times k = 1/(8 pi mu)) of the sources q in [begin, end) of
// `src` (tree order), q != qi, on a target at src position qi with radius ai; count += pairs.
void add_pairs_sorted(const SortedSources& src, int begin, int end, int qi, double ai, double mu, Moments m,
                      double* yi, long& count);

}  // namespace stokesian::trees
