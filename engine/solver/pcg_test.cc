#include "engine/solver/pcg.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>

#include <iostream>
#include <random>

namespace facets {
namespace {

// Normal equations of a least-squares problem shaped like a window: unknowns on a
// grid, observations couple the 3 corners of each grid triangle with random
// coefficients, plus a weak curvature-like smoothness term. Ill-conditioned enough
// that the preconditioner matters.
CsrMatrix GridNormalEquations(int n, Eigen::VectorXd* rhs) {
  std::mt19937 rng(7);
  std::normal_distribution<double> gauss(0.0, 1.0);
  auto id = [n](int i, int j) { return j * n + i; };
  std::vector<std::vector<int>> cliques;
  for (int j = 0; j + 1 < n; ++j) {
    for (int i = 0; i + 1 < n; ++i) {
      cliques.push_back({id(i, j), id(i + 1, j), id(i, j + 1)});
      cliques.push_back({id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  }
  for (int j = 0; j < n; ++j) {
    for (int i = 1; i + 1 < n; ++i) cliques.push_back({id(i - 1, j), id(i, j), id(i + 1, j)});
  }
  CsrMatrix normal = CsrMatrix::FromCliques(n * n, cliques);
  *rhs = Eigen::VectorXd::Zero(n * n);
  for (size_t c = 0; c < cliques.size(); ++c) {
    const auto& clique = cliques[c];
    const bool smoothness = clique.size() == 3 && c >= 2 * (n - 1) * (n - 1);
    const int observations = smoothness ? 1 : 20;
    for (int o = 0; o < observations; ++o) {
      Eigen::Vector3d a = smoothness ? Eigen::Vector3d(1, -2, 1) * 3.0
                                     : Eigen::Vector3d(gauss(rng), gauss(rng), gauss(rng)) * 0.3;
      const double l = gauss(rng);
      for (int r = 0; r < 3; ++r) {
        for (int s = 0; s < 3; ++s) normal.Add(clique[r], clique[s], a[r] * a[s]);
        (*rhs)[clique[r]] += a[r] * l;
      }
    }
  }
  return normal;
}

TEST(CsrMatrix, PatternFromCliquesIsSymmetricAndComplete) {
  const CsrMatrix m = CsrMatrix::FromCliques(5, {{0, 1}, {1, 2, 3}});
  // Rows: 0:{0,1} 1:{0,1,2,3} 2:{1,2,3} 3:{1,2,3} 4:{4}.
  EXPECT_EQ(m.nonZeros(), 2 + 4 + 3 + 3 + 1);
  EXPECT_GE(m.Find(3, 1), 0);
  EXPECT_GE(m.Find(1, 3), 0);
  EXPECT_EQ(m.Find(0, 2), -1);
  EXPECT_GE(m.Find(4, 4), 0);
}

TEST(Pcg, SsorMatchesDirectAndBeatsJacobi) {
  Eigen::VectorXd rhs;
  const CsrMatrix normal = GridNormalEquations(30, &rhs);
  const Eigen::VectorXd direct = SolveDirect(normal, rhs);

  PcgOptions ssor;
  ssor.relative_tolerance = 1e-12;
  Eigen::VectorXd x_ssor;
  const PcgSummary s = SolvePcg(normal, rhs, ssor, &x_ssor);
  PcgOptions jacobi = ssor;
  jacobi.preconditioner = Preconditioner::kJacobi;
  Eigen::VectorXd x_jacobi;
  const PcgSummary j = SolvePcg(normal, rhs, jacobi, &x_jacobi);

  const double err_ssor = (x_ssor - direct).norm() / direct.norm();
  const double err_jacobi = (x_jacobi - direct).norm() / direct.norm();
  std::cout << "SSOR-PCG iterations " << s.iterations << " rel.err " << err_ssor
            << "; Jacobi-PCG iterations " << j.iterations << " rel.err " << err_jacobi << "\n";
  EXPECT_TRUE(s.converged);
  EXPECT_TRUE(j.converged);
  EXPECT_LT(err_ssor, 1e-8);
  EXPECT_LT(err_jacobi, 1e-8);
  EXPECT_LE(2 * s.iterations, j.iterations);
}

TEST(Pcg, InverseDiagonalMatchesDenseInverse) {
  Eigen::VectorXd rhs;
  const CsrMatrix normal = GridNormalEquations(6, &rhs);
  const Eigen::MatrixXd dense_inverse = Eigen::MatrixXd(normal.ToEigen()).inverse();
  const std::vector<int> unknowns = {0, 7, 35};
  const Eigen::VectorXd diag = InverseDiagonal(normal, unknowns);
  for (size_t k = 0; k < unknowns.size(); ++k) {
    EXPECT_NEAR(diag[k], dense_inverse(unknowns[k], unknowns[k]),
                1e-10 * dense_inverse(unknowns[k], unknowns[k]));
  }
}

// The window solver: one analysis of the pattern, then a factorisation per set of
// values (two matrices with the same pattern, as two iterations of a window give).
TEST(SparseLdlt, AnalysesOnceAndMatchesDirectAndInverse) {
  Eigen::VectorXd rhs;
  CsrMatrix normal = GridNormalEquations(30, &rhs);
  SparseLdlt ldlt;
  ldlt.Analyze(normal);
  for (int round = 0; round < 2; ++round) {
    if (round == 1) {
      for (int i = 0; i < normal.rows(); ++i) normal.Add(i, i, 0.5 + 0.01 * i);  // new values, same pattern
    }
    ASSERT_TRUE(ldlt.Factorize(normal));
    const Eigen::VectorXd direct = SolveDirect(normal, rhs);
    const Eigen::VectorXd x = ldlt.Solve(rhs);
    EXPECT_LT((x - direct).norm() / direct.norm(), 1e-12);
    const std::vector<int> unknowns = {0, 7, 450, 899};
    const Eigen::VectorXd diag = ldlt.InverseDiagonal(unknowns);
    const Eigen::VectorXd reference = InverseDiagonal(normal, unknowns);
    for (size_t k = 0; k < unknowns.size(); ++k) EXPECT_NEAR(diag[k], reference[k], 1e-12 * reference[k]);
  }
  EXPECT_EQ(ldlt.analyses(), 1);
  // A matrix that is not positive definite is refused (the window falls back to PCG).
  for (int i = 0; i < normal.rows(); ++i) normal.values()[normal.diagonal_index()[i]] = -1.0;
  EXPECT_FALSE(ldlt.Factorize(normal));
}

TEST(Pcg, RejectsBadOptions) {
  PcgOptions options;
  options.ssor_omega = 2.0;
  std::string error;
  EXPECT_FALSE(options.Check(&error));
  EXPECT_NE(error.find("omega"), std::string::npos);
}

}  // namespace
}  // namespace facets
