// Solvers for the normal equations N x = b (symmetric positive definite, CSR):
// conjugate gradients with an SSOR preconditioner (the production solver, DESIGN.md
// section 5), with a Jacobi preconditioner and a sparse direct LDL^T as references
// for tests and benchmarks.
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <memory>
#include <string>
#include <vector>

#include "engine/solver/csr_matrix.h"

namespace facets {

enum class Preconditioner { kSsor, kJacobi, kNone };

struct PcgOptions {
  Preconditioner preconditioner = Preconditioner::kSsor;
  // SSOR relaxation factor omega in (0, 2); 1 is symmetric Gauss-Seidel.
  double ssor_omega = 1.2;
  // Stop when ||r|| <= relative_tolerance * ||b||. Coarse levels can use a looser
  // tolerance because finer levels correct what is left (the pipeline sets it).
  double relative_tolerance = 1e-10;
  int max_iterations = 2000;

  // Returns false and fills *error when an option is out of range.
  bool Check(std::string* error) const;
};

struct PcgSummary {
  int iterations = 0;
  double relative_residual = 0.0;
  bool converged = false;
};

// Solves N x = b; x holds the start value on entry (resized to zero if empty).
PcgSummary SolvePcg(const CsrMatrix& normal, const Eigen::VectorXd& rhs,
                    const PcgOptions& options, Eigen::VectorXd* x);

// Sparse direct solve (Eigen SimplicialLDLT) for reference. Throws if N is singular.
Eigen::VectorXd SolveDirect(const CsrMatrix& normal, const Eigen::VectorXd& rhs);

// Diagonal entries of N^-1 for the listed unknowns, exact, by a sparse LDL^T
// factorisation and one forward/backward solve per listed unknown. Used for the
// per-vertex standard deviations of a window (a few hundred geometry unknowns), where
// this costs far less than the adjustment itself.
Eigen::VectorXd InverseDiagonal(const CsrMatrix& normal, const std::vector<int>& unknowns);

// Sparse direct LDL^T (Eigen SimplicialLDLT, AMD ordering) for a sequence of normal
// matrices with one CSR pattern, e.g. the iterations of one window adjustment: the
// ordering and the symbolic factorisation are computed once (Analyze), every
// iteration only refactorises the values (Factorize). The window's pattern is fixed
// for one run (cliques of faces and curvature rings, not of what the images see).
class SparseLdlt {
 public:
  SparseLdlt();
  ~SparseLdlt();
  SparseLdlt(const SparseLdlt&) = delete;
  SparseLdlt& operator=(const SparseLdlt&) = delete;

  // Symbolic analysis of the pattern of `normal` (values ignored).
  void Analyze(const CsrMatrix& normal);
  // Numeric factorisation; re-analyses when the pattern differs from the analysed one
  // (row count or non-zero count changed). Returns false when N is not positive
  // definite (a zero or negative pivot).
  bool Factorize(const CsrMatrix& normal);
  bool factorized() const { return factorized_; }
  Eigen::VectorXd Solve(const Eigen::VectorXd& rhs) const;
  // Diagonal entries of N^-1 for the listed unknowns from the current factor.
  Eigen::VectorXd InverseDiagonal(const std::vector<int>& unknowns) const;
  // How often the pattern was analysed (1 per window run when it stays fixed).
  int analyses() const { return analyses_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  bool factorized_ = false;
  int analyses_ = 0;
};

}  // namespace facets
