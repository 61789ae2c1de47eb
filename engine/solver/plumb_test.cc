#include "engine/solver/plumb.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <random>

namespace facets {
namespace {

// The gradient against central differences on random faces, steep ones and flat ones.
TEST(Plumb, NormalZGradientMatchesFiniteDifferences) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  double worst = 0.0;
  for (int trial = 0; trial < 200; ++trial) {
    Eigen::Vector3d x[3];
    for (auto& p : x) p = Eigen::Vector3d(u(rng), u(rng), u(rng));
    Eigen::Vector3d gradient[3], unused[3];
    FaceNormalZ(x, gradient);
    const double eps = 1e-6;
    for (int k = 0; k < 3; ++k) {
      for (int c = 0; c < 3; ++c) {
        Eigen::Vector3d plus[3] = {x[0], x[1], x[2]}, minus[3] = {x[0], x[1], x[2]};
        plus[k][c] += eps;
        minus[k][c] -= eps;
        const double fd = (FaceNormalZ(plus, unused) - FaceNormalZ(minus, unused)) / (2 * eps);
        worst = std::max(worst, std::abs(fd - gradient[k][c]) / (1.0 + std::abs(fd)));
      }
    }
  }
  EXPECT_LT(worst, 1e-6);
}

TEST(Plumb, VerticalFaceHasZeroNormalZAndAFlatOneHasOne) {
  Eigen::Vector3d wall[3] = {{0, 0, 0}, {1, 0, 0}, {0, 0, 1}}, roof[3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  Eigen::Vector3d gradient[3];
  EXPECT_NEAR(FaceNormalZ(wall, gradient), 0.0, 1e-15);
  // The wall's top corner moved across the wall tilts it: |d n.z / d y| = 1 / height.
  EXPECT_NEAR(std::abs(gradient[2].y()), 1.0, 1e-12);
  EXPECT_NEAR(FaceNormalZ(roof, gradient), 1.0, 1e-15);
  Eigen::Vector3d degenerate[3] = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}};
  EXPECT_EQ(FaceNormalZ(degenerate, gradient), 0.0);
  EXPECT_TRUE(gradient[1].isZero());
}

}  // namespace
}  // namespace facets
