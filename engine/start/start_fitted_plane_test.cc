#include "engine/start/start_fitted_plane.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <stdexcept>

namespace facets {
namespace {

// Points on a vertical wall x = 2 (normal +-X), 4 m wide (y) and 3 m high (z), with
// 1 cm noise, plus 20% gross outliers up to 3 m in front of / behind it (trees, cars).
std::vector<Eigen::Vector3d> WallWithOutliers(int n, int outliers) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> y(-2.0, 2.0), z(0.0, 3.0), off(-3.0, 3.0);
  std::normal_distribution<double> noise(0.0, 0.01);
  std::vector<Eigen::Vector3d> points;
  for (int i = 0; i < n; ++i) points.emplace_back(2.0 + noise(rng), y(rng), z(rng));
  for (int i = 0; i < outliers; ++i) points.emplace_back(2.0 + off(rng), y(rng), z(rng));
  return points;
}

TEST(StartFittedPlane, VerticalWallWithOutliersIsFoundWithinTolerance) {
  const auto points = WallWithOutliers(800, 200);
  const Eigen::Vector3d viewpoint(10.0, 0.0, 1.5);  // street side, +X
  const FittedPlane plane = FitStartPlane(points, viewpoint);
  // Normal within 0.5 degrees of +X (towards the viewpoint), wall position within 1 cm.
  EXPECT_GT(plane.normal.x(), std::cos(0.5 * M_PI / 180.0));
  EXPECT_NEAR(plane.centre.x(), 2.0, 0.01);
  EXPECT_NEAR(plane.tilt_deg, 90.0, 0.5);
  // Outliers rejected: the kept RMS is the noise (1 cm), not the 3 m spread.
  EXPECT_LT(plane.rms, 0.02);
  EXPECT_GE(plane.kept, 780);
  EXPECT_LE(plane.kept, 870);  // an outlier closer than 3 sigma may stay
  EXPECT_EQ(plane.total, 1000);
  // Extent: the 2..98 % quantiles of the wall, 4 x 3 m -> about 3.84 x 2.88 m.
  const Eigen::Vector2d size = plane.max_uv - plane.min_uv;
  EXPECT_NEAR(std::max(size.x(), size.y()), 3.84, 0.15);
  EXPECT_NEAR(std::min(size.x(), size.y()), 2.88, 0.15);
  EXPECT_NEAR(plane.axis_u.cross(plane.axis_v).dot(plane.normal), 1.0, 1e-12);
}

TEST(StartFittedPlane, MeshLiesInThePlaneAndFacesTheViewpoint) {
  const auto points = WallWithOutliers(500, 0);
  const FittedPlane plane = FitStartPlane(points, Eigen::Vector3d(-10.0, 0.0, 1.5));
  EXPECT_LT(plane.normal.x(), -0.999);  // towards the viewpoint at -X this time
  const TinMesh mesh = MakeFittedPlaneMesh(plane, 0.25);
  ASSERT_GT(mesh.n_faces(), 100u);
  for (auto vh : mesh.vertices()) {
    EXPECT_NEAR(plane.normal.dot(ToEigen(mesh.point(vh)) - plane.centre), 0.0, 1e-9);
    EXPECT_GT(ToEigen(mesh.normal(vh)).dot(plane.normal), 0.999);
  }
}

TEST(StartFittedPlane, HorizontalTerrainGivesSmallTilt) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> xy(-50.0, 50.0);
  std::normal_distribution<double> noise(0.0, 0.3);
  std::vector<Eigen::Vector3d> points;
  for (int i = 0; i < 400; ++i) points.emplace_back(xy(rng), xy(rng), 70.0 + noise(rng));
  const FittedPlane plane = FitStartPlane(points, Eigen::Vector3d(0.0, 0.0, 300.0));
  EXPECT_LT(plane.tilt_deg, 1.0);
  EXPECT_GT(plane.normal.z(), 0.0);
  EXPECT_NEAR(plane.centre.z(), 70.0, 0.1);
}

TEST(StartFittedPlane, TooFewOrCollinearPointsAreClearErrors) {
  std::vector<Eigen::Vector3d> few(5, Eigen::Vector3d::Zero());
  EXPECT_THROW(FitStartPlane(few, Eigen::Vector3d::UnitZ()), std::runtime_error);
  std::vector<Eigen::Vector3d> line;
  for (int i = 0; i < 50; ++i) line.emplace_back(i, 2.0 * i, 0.0);
  EXPECT_THROW(FitStartPlane(line, Eigen::Vector3d::UnitZ()), std::runtime_error);
}

}  // namespace
}  // namespace facets
