#pragma once
// Clusters of spheres: the connected components of a bond graph, and each cluster's size and shape.
// The definitions are written once, here and in docs/clusters.md; `stokesian clusters` (any
// trajectory) and the cloud observables of a run (engine/observers.cpp) use them.
//
// Bonds. Spheres i and j are bonded when their surface gap h_ij = |r_ij| - a_i - a_j <= bond_gap
//   (r_ij the nearest periodic image). A cluster is a connected component of the bond graph (a
//   chain of bonds joins its ends however far apart they are); a sphere without bonds is a cluster
//   of size 1.
// Friends of friends (clouds): linked when the centre distance |r_ij| <= link, i.e. the bond graph
//   with every radius taken as zero (link_by_centres).
// Per cluster c, with weights m_i = a_i^3 (mass of spheres of one density):
//   size n_c; mass M_c = sum m_i [a^3] (volume 4/3 pi M_c);
//   centre x_c = sum m_i u_i / M_c, u_i the positions unwrapped along the bonds (periodic boxes);
//   radius of gyration R_g^2 = sum m_i (|u_i - x_c|^2 + 3/5 a_i^2) / M_c, the spheres' own mass
//     included, so one sphere has R_g = sqrt(3/5) a;
//   maximum Feret diameter D_F = max_{i,j in c} (|u_i - u_j| + a_i + a_j), i = j allowed: the
//     largest caliper width of the union of the spheres. Exact: the width along a unit vector e is
//     max_i (e.u_i + a_i) - min_j (e.u_j - a_j) <= |u_i - u_j| + a_i + a_j, with equality for e
//     along u_i - u_j. O(n_c^2) per cluster;
//   velocity V_c = sum m_i v_i / M_c (mass-weighted), when velocities are given;
//   spanning: in a periodic box, a cycle of bonds winds around the box (the cluster reaches its own
//     image); x_c, R_g and D_F are then undefined and reported as NaN.
// Fractal dimension, ensemble estimator: the least-squares slope D_f of ln n_c against
//   ln(R_g,c / a_m) over the clusters with n_c >= min_size (mass-radius relation
//   n = k_f (R_g / a_m)^{D_f}; a_m the mean radius of all spheres). Undefined (NaN) with fewer than
//   3 such clusters or when their R_g span less than a factor kFractalMinSpan.
#include "engine/core/domain.hpp"
#include "engine/core/types.hpp"

#include <vector>

namespace stokesian::trees {

struct Clusters {
  // label[i]: cluster of sphere i. Clusters are numbered by decreasing size, ties by their lowest
  // member index; members[c] lists cluster c's spheres in increasing order.
  std::vector<int> label;
  std::vector<std::vector<int>> members;
  // The bonds found (i < j, r = x_i - x_j nearest image), for unwrapping.
  struct Bond {
    int i, j;
    Vec3 r;
  };
  std::vector<Bond> bonds;
};

// Components of the bond graph h_ij <= bond_gap (cell list, O(N) at bounded density; every box).
// Spheres with skip[i] != 0 (e.g. wall particles) take part in nothing and get label -1.
Clusters find_clusters(const std::vector<Vec3>& x, const std::vector<double>& radius, const Domain& domain,
                       double bond_gap, const std::vector<char>* skip = nullptr);
// Friends of friends: components of |r_ij| <= link.
Clusters link_by_centres(const std::vector<Vec3>& x, const Domain& domain, double link,
                         const std::vector<char>* skip = nullptr);
// The reference twin: every pair by the plain double loop, components by repeated label
// propagation (no union-find), same numbering.
Clusters find_clusters_reference(const std::vector<Vec3>& x, const std::vector<double>& radius, const Domain& domain,
                                 double bond_gap, const std::vector<char>* skip = nullptr);

struct ClusterShape {
  long size = 0;
  double mass = 0.0;                // sum a_i^3 [a^3]
  Vec3 centre = Vec3::Zero();       // mass-weighted [a]
  double radius_of_gyration = 0.0;  // [a]
  double feret = 0.0;               // maximum Feret diameter [a]
  Vec3 velocity = Vec3::Zero();     // mass-weighted; zero when no velocities are given
  bool spanning = false;            // periodic: winds around the box (centre, R_g, D_F are NaN)
};

// Shapes of every cluster, in the numbering of `c`. velocity may be empty.
std::vector<ClusterShape> cluster_shapes(const Clusters& c, const std::vector<Vec3>& x,
                                         const std::vector<double>& radius, const Domain& domain,
                                         const std::vector<Vec3>& velocity = {});

// Number of clusters of each size: h[n] for n = 0..(largest size); h[0] = 0.
std::vector<long> size_histogram(const Clusters& c);

inline constexpr double kFractalMinSpan = 1.5;
struct FractalFit {
  double dimension = 0.0;  // D_f, NaN when undefined
  double prefactor = 0.0;  // k_f
  long clusters = 0;       // clusters used
};
FractalFit fractal_dimension(const std::vector<ClusterShape>& shapes, double mean_radius, long min_size);

}  // namespace stokesian::trees
