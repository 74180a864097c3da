#pragma once
// `stokesian clusters`: cluster analysis of a trajectory (trees/clusters.hpp; definitions in
// docs/clusters.md). Per analysed frame: bonds h_ij <= bond_gap, connected components, number of
// clusters and their size histogram, the growth rate of each size class, and per cluster its mass,
// centre, radius of gyration, maximum Feret diameter and (when the trajectory records velocity)
// mass-weighted velocity; the ensemble fractal dimension per frame. Wall particles and fixed
// particles of the stored scene, and the empty slots of open channels, take no part.
// Writes an HDF5 file (docs/clusters.md "Output") and prints one line per analysed frame.
#include <cstdint>
#include <cstdio>
#include <string>

namespace stokesian::app {

struct ClusterOptions {
  double bond_gap = 0.1;  // [a]: spheres with surface gap <= bond_gap are bonded
  long min_size = 4;      // clusters of at least this size enter the fractal-dimension fit
  long every = 1;         // analyse every k-th frame
  std::string out;        // HDF5 output; default <trajectory without .h5>.clusters.h5
};

// Throws IoError for an unreadable trajectory, ConfigError for a bad option (naming it and its range).
int clusters(const std::string& trajectory, const ClusterOptions& opt, std::FILE* out);

}  // namespace stokesian::app
