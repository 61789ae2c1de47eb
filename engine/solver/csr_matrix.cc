#include "engine/solver/csr_matrix.h"

#include <algorithm>
#include <cassert>
#include <stdexcept>

namespace facets {

CsrMatrix CsrMatrix::FromCliques(int num_rows,
                                 const std::vector<std::vector<int>>& cliques) {
  // Collect the column sets row by row, then sort and deduplicate. Each row's set
  // is small (the unknowns of the faces around one vertex), so vectors beat sets.
  std::vector<std::vector<int>> row_cols(num_rows);
  for (const auto& clique : cliques) {
    for (int i : clique) {
      if (i < 0 || i >= num_rows) throw std::out_of_range("CsrMatrix: index in clique");
      auto& cols = row_cols[i];
      cols.insert(cols.end(), clique.begin(), clique.end());
    }
  }
  CsrMatrix m;
  m.num_rows_ = num_rows;
  m.row_ptr_.assign(num_rows + 1, 0);
  m.diagonal_.assign(num_rows, -1);
  for (int i = 0; i < num_rows; ++i) {
    auto& cols = row_cols[i];
    cols.push_back(i);  // every row has its diagonal, even an unobserved unknown
    std::sort(cols.begin(), cols.end());
    cols.erase(std::unique(cols.begin(), cols.end()), cols.end());
    m.row_ptr_[i + 1] = m.row_ptr_[i] + static_cast<int64_t>(cols.size());
  }
  m.cols_.reserve(m.row_ptr_.back());
  for (int i = 0; i < num_rows; ++i) {
    for (int c : row_cols[i]) {
      if (c == i) m.diagonal_[i] = static_cast<int64_t>(m.cols_.size());
      m.cols_.push_back(c);
    }
  }
  m.values_.assign(m.cols_.size(), 0.0);
  return m;
}

int64_t CsrMatrix::Find(int i, int j) const {
  const auto begin = cols_.begin() + row_ptr_[i];
  const auto end = cols_.begin() + row_ptr_[i + 1];
  const auto it = std::lower_bound(begin, end, j);
  if (it == end || *it != j) return -1;
  return it - cols_.begin();
}

void CsrMatrix::Add(int i, int j, double v) {
  const int64_t k = Find(i, j);
  assert(k >= 0 && "CsrMatrix::Add outside the pattern");
  values_[k] += v;
}

void CsrMatrix::SetZero() { std::fill(values_.begin(), values_.end(), 0.0); }

void CsrMatrix::Multiply(const Eigen::VectorXd& x, Eigen::VectorXd* y) const {
  y->resize(num_rows_);
  for (int i = 0; i < num_rows_; ++i) {
    double sum = 0.0;
    for (int64_t k = row_ptr_[i]; k < row_ptr_[i + 1]; ++k) sum += values_[k] * x[cols_[k]];
    (*y)[i] = sum;
  }
}

Eigen::SparseMatrix<double> CsrMatrix::ToEigen() const {
  std::vector<Eigen::Triplet<double>> triplets;
  triplets.reserve(values_.size());
  for (int i = 0; i < num_rows_; ++i) {
    for (int64_t k = row_ptr_[i]; k < row_ptr_[i + 1]; ++k) {
      triplets.emplace_back(i, cols_[k], values_[k]);
    }
  }
  Eigen::SparseMatrix<double> a(num_rows_, num_rows_);
  a.setFromTriplets(triplets.begin(), triplets.end());
  return a;
}

}  // namespace facets
