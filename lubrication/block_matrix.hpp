#pragma once
// Symmetric block-sparse storage of the near-field resistance R_nf (lubrication/near_field.hpp).
//
// A is n d x n d, symmetric, made of d x d blocks A_ij (d = 3, 6, 11 for F, FT, FTS). Only the
// diagonal and upper blocks (i <= j) are stored, each once and column-major, block row by block row:
// the diagonal block first, then the partners j > i ascending. The product y = A x is
//
//     y_i = sum_{j >= i} A_ij x_j  +  sum_{k < i} A_ki^T x_k,
//
// which reads every stored block once: at 10^4 spheres, phi 0.4, FTS, cutoff 6 that is 0.45 GB of
// values, against 1.2 GB of values and row indices for both triangles in compressed columns.
// Determinism: the block rows are split into kChunks slices of about equal stored size, a partition
// that does not depend on the thread count. A slice writes its rows' first sums straight into y and
// its transposed parts A_ki^T x_k into a buffer of its own; the buffers are added in slice order.
// So y is bitwise the same on any number of threads.
#include "engine/core/types.hpp"
#include "lubrication/cholmod_factor.hpp"

#include <vector>

namespace stokesian::lubrication {

class SymmetricBlockMatrix {
 public:
  static constexpr int kChunks = 8;

  /// Pattern: block row i holds its diagonal block iff `diagonal[i]`, then the blocks of
  /// `upper[i]` (partners j > i, ascending). Values are left undefined; the storage of a previous
  /// pattern is reused when it is large enough.
  void reset(long n, int d, const std::vector<char>& diagonal, const std::vector<std::vector<int>>& upper);

  long block_rows() const { return n_; }
  int block_size() const { return d_; }
  long rows() const { return n_ * d_; }
  long stored_blocks() const { return long(col_.size()); }
  long row_begin(long i) const { return start_[std::size_t(i)]; }
  long row_end(long i) const { return start_[std::size_t(i) + 1]; }
  int col(long b) const { return col_[std::size_t(b)]; }
  double* block(long b) { return val_.data() + std::size_t(b) * std::size_t(d_ * d_); }
  const double* block(long b) const { return val_.data() + std::size_t(b) * std::size_t(d_ * d_); }
  /// Index of the stored block (i, j), i <= j; -1 if it is not stored.
  long find(long i, long j) const;

  /// y = A x (parallel over the fixed slices; the same bits for any thread count).
  void multiply(const VecX& x, VecX& y) const;
  /// Both triangles in compressed columns (reference and small solvers).
  SparseMatrix to_sparse() const;

 private:
  long n_ = 0;
  int d_ = 0;
  std::vector<long> start_;   // n + 1 offsets into col_
  std::vector<int> col_;      // block column of every stored block
  std::vector<double> val_;   // d^2 values per stored block
  std::vector<long> slice_;   // kChunks + 1 block-row boundaries
  std::vector<long> offset_;  // kChunks + 1 starts of the slices' ranges in buffer_
  // Transposed parts, one range [slice start, n) d per slice; multiply() is therefore not safe to
  // call concurrently on one matrix.
  mutable std::vector<double> buffer_;
};

}  // namespace stokesian::lubrication
