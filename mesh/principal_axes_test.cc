#include "mesh/principal_axes.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <cmath>
#include <stdexcept>

namespace facets {
namespace {

// Points on a 5 x 3 grid (2 m by 1 m steps) in a tilted plane: the smallest axis is the plane's normal,
// the largest runs along the grid's long side, the eigenvalues are the sums of squares.
TEST(PrincipalAxesTest, PlaneNormalAndLineDirectionOfAGrid) {
  const Eigen::Vector3d u = Eigen::Vector3d(1, 1, 0).normalized();
  const Eigen::Vector3d v = Eigen::Vector3d(-1, 1, 1).normalized();
  const Eigen::Vector3d normal = u.cross(v).normalized();
  const Eigen::Vector3d centre(10, -5, 3);
  std::vector<Eigen::Vector3d> points;
  double su = 0.0, sv = 0.0;
  for (int i = -2; i <= 2; ++i) {
    for (int j = -1; j <= 1; ++j) {
      points.push_back(centre + 2.0 * i * u + 1.0 * j * v);
      su += 4.0 * i * i;
      sv += 1.0 * j * j;
    }
  }
  const PrincipalAxes fit = FitPrincipalAxes(points);
  EXPECT_LT((fit.centre - centre).norm(), 1e-12);
  EXPECT_NEAR(std::abs(fit.Normal().dot(normal)), 1.0, 1e-12);
  EXPECT_NEAR(std::abs(fit.Direction().dot(u)), 1.0, 1e-12);
  EXPECT_NEAR(fit.eigenvalues(0), 0.0, 1e-9);
  EXPECT_NEAR(fit.eigenvalues(1), sv, 1e-9);
  EXPECT_NEAR(fit.eigenvalues(2), su, 1e-9);
  EXPECT_NEAR(fit.axes.col(0).norm(), 1.0, 1e-12);
}

TEST(PrincipalAxesTest, NoPointsIsAnError) {
  EXPECT_THROW(FitPrincipalAxes({}), std::invalid_argument);
}

}  // namespace
}  // namespace facets
