#pragma once
// Sizes below which a kernel's OpenMP loop runs on one thread (thread start-up costs more than the
// loop), gathered so that the step's task graph (engine/simulation.cpp) can tell which phases use
// every thread on their own. Measured on the 2-core benchmark machine (docs/benchmarks.md).
namespace stokesian::parallel {

constexpr long kDirectProductParticles = 256;  // direct far-field product, rows per particle
constexpr long kPairForcePairs = 2048;         // pair-force evaluation, per pair
constexpr long kNeighborParticles = 4096;      // cell-list neighbour search, per particle
constexpr long kNearFieldPairs = 64;           // near-field pair blocks (~50 us each)

}  // namespace stokesian::parallel
