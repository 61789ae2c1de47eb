#include "engine/solver/pcg.h"

#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace facets {
namespace {

// z = M^-1 r for the SSOR preconditioner of N = L + D + L^T:
//   M = omega / (2 - omega) * (D/omega + L) (D/omega)^-1 (D/omega + L^T).
// Forward sweep over the strictly lower part, scale by D/omega, backward sweep over
// the strictly upper part; both use the full CSR rows (columns sorted).
void ApplySsor(const CsrMatrix& n, double omega, const Eigen::VectorXd& r,
               Eigen::VectorXd* z) {
  const int rows = n.rows();
  const auto& row_ptr = n.row_ptr();
  const auto& cols = n.cols();
  const auto& values = n.values();
  const auto& diag = n.diagonal_index();
  Eigen::VectorXd& y = *z;
  y.resize(rows);
  for (int i = 0; i < rows; ++i) {
    double sum = r[i];
    for (int64_t k = row_ptr[i]; k < diag[i]; ++k) sum -= values[k] * y[cols[k]];
    y[i] = sum * omega / values[diag[i]];
  }
  for (int i = 0; i < rows; ++i) y[i] *= values[diag[i]] / omega;
  for (int i = rows - 1; i >= 0; --i) {
    double sum = y[i];
    for (int64_t k = diag[i] + 1; k < row_ptr[i + 1]; ++k) sum -= values[k] * y[cols[k]];
    y[i] = sum * omega / values[diag[i]];
  }
  y *= (2.0 - omega) / omega;
}

void ApplyPreconditioner(const CsrMatrix& n, const PcgOptions& options,
                         const Eigen::VectorXd& r, Eigen::VectorXd* z) {
  switch (options.preconditioner) {
    case Preconditioner::kSsor:
      ApplySsor(n, options.ssor_omega, r, z);
      return;
    case Preconditioner::kJacobi:
      z->resize(r.size());
      for (int i = 0; i < n.rows(); ++i) (*z)[i] = r[i] / n.Diagonal(i);
      return;
    case Preconditioner::kNone:
      *z = r;
      return;
  }
}

}  // namespace

bool PcgOptions::Check(std::string* error) const {
  if (!(ssor_omega > 0.0 && ssor_omega < 2.0)) {
    *error = "ssor_omega must lie in (0, 2)";
    return false;
  }
  if (!(relative_tolerance > 0.0)) {
    *error = "relative_tolerance must be positive";
    return false;
  }
  if (max_iterations <= 0) {
    *error = "max_iterations must be positive";
    return false;
  }
  return true;
}

PcgSummary SolvePcg(const CsrMatrix& normal, const Eigen::VectorXd& rhs,
                    const PcgOptions& options, Eigen::VectorXd* x) {
  std::string error;
  if (!options.Check(&error)) throw std::invalid_argument("PcgOptions: " + error);
  for (int i = 0; i < normal.rows(); ++i) {
    if (!(normal.Diagonal(i) > 0.0)) {
      throw std::runtime_error("SolvePcg: normal matrix has a non-positive diagonal at row " +
                               std::to_string(i) + " (unknown without observations?)");
    }
  }
  if (x->size() != rhs.size()) *x = Eigen::VectorXd::Zero(rhs.size());
  PcgSummary summary;
  const double rhs_norm = rhs.norm();
  if (rhs_norm == 0.0) {
    x->setZero();
    summary.converged = true;
    return summary;
  }
  Eigen::VectorXd r, z, p, q;
  normal.Multiply(*x, &q);
  r = rhs - q;
  ApplyPreconditioner(normal, options, r, &z);
  p = z;
  double rz = r.dot(z);
  const double target = options.relative_tolerance * rhs_norm;
  for (int iteration = 0; iteration < options.max_iterations; ++iteration) {
    if (r.norm() <= target) break;
    normal.Multiply(p, &q);
    const double alpha = rz / p.dot(q);
    *x += alpha * p;
    r -= alpha * q;
    ++summary.iterations;
    ApplyPreconditioner(normal, options, r, &z);
    const double rz_next = r.dot(z);
    p = z + (rz_next / rz) * p;
    rz = rz_next;
  }
  summary.relative_residual = r.norm() / rhs_norm;
  summary.converged = r.norm() <= target;
  return summary;
}

Eigen::VectorXd SolveDirect(const CsrMatrix& normal, const Eigen::VectorXd& rhs) {
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(normal.ToEigen());
  if (ldlt.info() != Eigen::Success) {
    throw std::runtime_error("SolveDirect: normal matrix is singular or not positive definite");
  }
  return ldlt.solve(rhs);
}

struct SparseLdlt::Impl {
  // CSR of a symmetric matrix with both triangles stored = its CSC: the Eigen matrix
  // shares the pattern and gets the values copied in order.
  Eigen::SparseMatrix<double> matrix;
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt;
  int64_t nnz = -1;
};

SparseLdlt::SparseLdlt() : impl_(std::make_unique<Impl>()) {}
SparseLdlt::~SparseLdlt() = default;

void SparseLdlt::Analyze(const CsrMatrix& normal) {
  impl_->matrix = normal.ToEigen();
  impl_->matrix.makeCompressed();
  impl_->nnz = normal.nonZeros();
  impl_->ldlt.analyzePattern(impl_->matrix);
  factorized_ = false;
  ++analyses_;
}

bool SparseLdlt::Factorize(const CsrMatrix& normal) {
  if (impl_->nnz != normal.nonZeros() || impl_->matrix.rows() != normal.rows()) Analyze(normal);
  const std::vector<double>& values = normal.values();
  std::copy(values.begin(), values.end(), impl_->matrix.valuePtr());
  impl_->ldlt.factorize(impl_->matrix);
  factorized_ = impl_->ldlt.info() == Eigen::Success;
  if (factorized_) {
    const auto d = impl_->ldlt.vectorD();
    for (Eigen::Index i = 0; i < d.size(); ++i) {
      if (!(d[i] > 0.0)) {
        factorized_ = false;
        break;
      }
    }
  }
  return factorized_;
}

Eigen::VectorXd SparseLdlt::Solve(const Eigen::VectorXd& rhs) const {
  if (!factorized_) throw std::logic_error("SparseLdlt::Solve: no factor");
  return impl_->ldlt.solve(rhs);
}

Eigen::VectorXd SparseLdlt::InverseDiagonal(const std::vector<int>& unknowns) const {
  if (!factorized_) throw std::logic_error("SparseLdlt::InverseDiagonal: no factor");
  Eigen::VectorXd out(unknowns.size());
  Eigen::VectorXd unit = Eigen::VectorXd::Zero(impl_->matrix.rows());
  for (size_t k = 0; k < unknowns.size(); ++k) {
    unit[unknowns[k]] = 1.0;
    out[k] = impl_->ldlt.solve(unit)[unknowns[k]];
    unit[unknowns[k]] = 0.0;
  }
  return out;
}

Eigen::VectorXd InverseDiagonal(const CsrMatrix& normal, const std::vector<int>& unknowns) {
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(normal.ToEigen());
  if (ldlt.info() != Eigen::Success) {
    throw std::runtime_error("InverseDiagonal: normal matrix is singular");
  }
  Eigen::VectorXd out(unknowns.size());
  Eigen::VectorXd unit = Eigen::VectorXd::Zero(normal.rows());
  for (size_t k = 0; k < unknowns.size(); ++k) {
    unit[unknowns[k]] = 1.0;
    out[k] = ldlt.solve(unit)[unknowns[k]];
    unit[unknowns[k]] = 0.0;
  }
  return out;
}

}  // namespace facets
