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

// A wall x = 0 (seen from +X), 8 m wide (y) and 4 m high (z), with a basin 3 m wide, 1 m
// high, standing 1.2 m in front of it (x = 1.2) in the middle; tie points on both, 1 cm noise.
std::vector<Eigen::Vector3d> WallWithBasin() {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> y(-4.0, 4.0), z(0.0, 4.0);
  std::normal_distribution<double> noise(0.0, 0.01);
  std::vector<Eigen::Vector3d> points;
  for (int i = 0; i < 3000; ++i) {
    const double py = y(rng), pz = z(rng);
    const bool on_basin = std::abs(py) < 1.5 && pz < 1.0;
    points.emplace_back((on_basin ? 1.2 : 0.0) + noise(rng), py, pz);
  }
  return points;
}

TEST(StartFittedPlane, TiePointMeshFollowsTheReliefAlongTheNormal) {
  const auto points = WallWithBasin();
  const FittedPlane plane = FitStartPlane(points, Eigen::Vector3d(10.0, 0.0, 1.5));
  EXPECT_GT(plane.normal.x(), 0.99);
  TiePointStartReport report;
  const TinMesh mesh = MakeFittedTiePointMesh(plane, points, 0.5, {}, &report);
  EXPECT_EQ(report.nodes_from_plane, 0);
  // Nodes on the basin's front stand at x = 1.2 within 0.2 m (the start's smoothing pass
  // pulls a node beside a 1.2 m step about 0.15 m towards its neighbours), nodes well away
  // from it on the wall at x = 0 within 5 cm; faces look to +X.
  int on_basin = 0, on_wall = 0;
  for (auto vh : mesh.vertices()) {
    const Eigen::Vector3d p = ToEigen(mesh.point(vh));
    if (std::abs(p.y()) < 1.0 && p.z() > 0.1 && p.z() < 0.7) {
      EXPECT_NEAR(p.x(), 1.2, 0.2) << p.transpose();
      ++on_basin;
    } else if ((std::abs(p.y()) > 2.0 && std::abs(p.y()) < 3.5 && p.z() > 0.3 && p.z() < 3.7) || p.z() > 1.5) {
      if (p.z() < 3.7 && std::abs(p.y()) < 3.7) {
        EXPECT_NEAR(p.x(), 0.0, 0.05) << p.transpose();
        ++on_wall;
      }
    }
  }
  EXPECT_GE(on_basin, 4);
  EXPECT_GE(on_wall, 20);
  for (auto fh : mesh.faces()) EXPECT_GT(ToEigen(mesh.calc_face_normal(fh)).dot(plane.normal), 0.0);
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
