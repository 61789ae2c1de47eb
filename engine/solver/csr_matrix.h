// Symmetric sparse matrices in compressed row storage (both triangles stored), built
// directly from a sparsity pattern: the normal equations of facets stereo vision are
// sparse and irregular, and are assembled straight into this layout without a dense
// or triplet intermediate (DESIGN.md section 5).
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <cstdint>
#include <vector>

namespace facets {

class CsrMatrix {
 public:
  CsrMatrix() = default;

  // Pattern from cliques: every pair (i, j) of unknowns that appear together in one
  // clique gets a slot (including i == j). Columns of each row are sorted.
  static CsrMatrix FromCliques(int num_rows, const std::vector<std::vector<int>>& cliques);

  int rows() const { return num_rows_; }
  int64_t nonZeros() const { return static_cast<int64_t>(cols_.size()); }

  const std::vector<int64_t>& row_ptr() const { return row_ptr_; }
  const std::vector<int>& cols() const { return cols_; }
  std::vector<double>& values() { return values_; }
  const std::vector<double>& values() const { return values_; }

  // Index of slot (i, j) in values(), or -1 when (i, j) is not in the pattern.
  int64_t Find(int i, int j) const;
  // values()[Find(i, j)] += v; (i, j) must be in the pattern (asserted).
  void Add(int i, int j, double v);
  void SetZero();

  // y = A x.
  void Multiply(const Eigen::VectorXd& x, Eigen::VectorXd* y) const;
  double Diagonal(int i) const { return values_[diagonal_[i]]; }
  const std::vector<int64_t>& diagonal_index() const { return diagonal_; }

  // For reference solvers and tests.
  Eigen::SparseMatrix<double> ToEigen() const;

 private:
  int num_rows_ = 0;
  std::vector<int64_t> row_ptr_;
  std::vector<int> cols_;
  std::vector<double> values_;
  std::vector<int64_t> diagonal_;
};

}  // namespace facets
