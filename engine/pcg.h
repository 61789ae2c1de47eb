// Solvers for the normal equations N x = b (symmetric positive definite, CSR):
// conjugate gradients with an SSOR preconditioner (the production solver, DESIGN.md
// section 5), with a Jacobi preconditioner and a sparse direct LDL^T as references
// for tests and benchmarks.
#pragma once

#include <Eigen/Core>
#include <string>

#include "engine/csr_matrix.h"

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

}  // namespace facets
