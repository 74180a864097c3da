#include "lubrication/block_matrix.hpp"

#include <algorithm>
#include <stdexcept>

namespace stokesian::lubrication {

void SymmetricBlockMatrix::reset(long n, int d, const std::vector<char>& diagonal,
                                 const std::vector<std::vector<int>>& upper) {
  if (d < 1 || d > 11) throw std::invalid_argument("SymmetricBlockMatrix::reset: block size d must be 1 ... 11");
  if (long(diagonal.size()) != n || long(upper.size()) != n)
    throw std::invalid_argument("SymmetricBlockMatrix::reset: need n diagonal flags and n partner lists");
  n_ = n;
  d_ = d;
  start_.assign(std::size_t(n) + 1, 0);
  long total = 0;
  for (long i = 0; i < n; ++i) {
    start_[std::size_t(i)] = total;
    total += (diagonal[std::size_t(i)] ? 1 : 0) + long(upper[std::size_t(i)].size());
  }
  start_[std::size_t(n)] = total;
  col_.resize(std::size_t(total));
  for (long i = 0; i < n; ++i) {
    long b = start_[std::size_t(i)];
    if (diagonal[std::size_t(i)]) col_[std::size_t(b++)] = int(i);
    for (int j : upper[std::size_t(i)]) {
      if (j <= i) throw std::invalid_argument("SymmetricBlockMatrix::reset: upper partners need j > i");
      col_[std::size_t(b++)] = j;
    }
  }
  val_.resize(std::size_t(total) * std::size_t(d * d));  // keeps the capacity
  // Slices of about total / kChunks stored blocks each.
  slice_.assign(kChunks + 1, n);
  slice_[0] = 0;
  long i = 0;
  for (int c = 1; c < kChunks; ++c) {
    const long target = (total * c) / kChunks;
    while (i < n && start_[std::size_t(i)] < target) ++i;
    slice_[std::size_t(c)] = i;
  }
  offset_.assign(kChunks + 1, 0);
  for (int c = 0; c < kChunks; ++c) offset_[std::size_t(c) + 1] = offset_[std::size_t(c)] + (n - slice_[std::size_t(c)]) * d;
  buffer_.resize(std::size_t(offset_[kChunks]));
}

long SymmetricBlockMatrix::find(long i, long j) const {
  const auto b = col_.begin() + start_[std::size_t(i)], e = col_.begin() + start_[std::size_t(i) + 1];
  if (b == e) return -1;
  if (*b == int(i)) {
    if (j == i) return start_[std::size_t(i)];
    const auto it = std::lower_bound(b + 1, e, int(j));
    return it != e && *it == int(j) ? long(it - col_.begin()) : -1;
  }
  const auto it = std::lower_bound(b, e, int(j));
  return it != e && *it == int(j) ? long(it - col_.begin()) : -1;
}

void SymmetricBlockMatrix::multiply(const VecX& x, VecX& y) const {
  const long N = n_ * d_;
  if (x.size() != N) throw std::invalid_argument("SymmetricBlockMatrix::multiply: size mismatch");
  y.resize(N);
  if (N == 0) return;  // also a matrix never reset
  const int d = d_;
  const long dd = long(d) * d;
  const double* xv = x.data();
  double* yv = y.data();
#pragma omp parallel
  {
#pragma omp for schedule(dynamic, 1)
    for (int c = 0; c < kChunks; ++c) {
      const long r0 = slice_[std::size_t(c)], r1 = slice_[std::size_t(c) + 1];
      double* t = buffer_.data() + offset_[std::size_t(c)] - r0 * d;  // t[row] for rows >= r0 d
      std::fill(t + r0 * d, t + N, 0.0);
      double yi[11];
      for (long i = r0; i < r1; ++i) {
        std::fill_n(yi, d, 0.0);
        const double* xi = xv + i * d;
        for (long b = start_[std::size_t(i)]; b < start_[std::size_t(i) + 1]; ++b) {
          const long j = col_[std::size_t(b)];
          const double* B = val_.data() + b * dd;
          const double* xj = xv + j * d;
          for (int v = 0; v < d; ++v) {
            const double s = xj[v];
            const double* Bv = B + v * d;
            for (int u = 0; u < d; ++u) yi[u] += Bv[u] * s;
          }
          if (j != i) {
            double* tj = t + j * d;
            for (int v = 0; v < d; ++v) {
              const double* Bv = B + v * d;
              double s = 0.0;
              for (int u = 0; u < d; ++u) s += Bv[u] * xi[u];
              tj[v] += s;
            }
          }
        }
        std::copy_n(yi, d, yv + i * d);
      }
    }
    // y += the slices' buffers, in slice order.
#pragma omp for schedule(static)
    for (long k = 0; k < N; ++k) {
      double s = yv[k];
      for (int c = 0; c < kChunks; ++c) {
        const long lo = slice_[std::size_t(c)] * d;
        if (k >= lo) s += buffer_[std::size_t(offset_[std::size_t(c)] + k - lo)];
      }
      yv[k] = s;
    }
  }
}

SparseMatrix SymmetricBlockMatrix::to_sparse() const {
  const int d = d_;
  std::vector<Eigen::Triplet<double, int>> t;
  t.reserve(std::size_t(2 * stored_blocks()) * std::size_t(d * d));
  for (long i = 0; i < n_; ++i)
    for (long b = start_[std::size_t(i)]; b < start_[std::size_t(i) + 1]; ++b) {
      const long j = col_[std::size_t(b)];
      const double* B = block(b);
      for (int v = 0; v < d; ++v)
        for (int u = 0; u < d; ++u) {
          t.emplace_back(int(i * d + u), int(j * d + v), B[v * d + u]);
          if (j != i) t.emplace_back(int(j * d + v), int(i * d + u), B[v * d + u]);
        }
    }
  SparseMatrix R(n_ * d, n_ * d);
  R.setFromTriplets(t.begin(), t.end());
  return R;
}

}  // namespace stokesian::lubrication
