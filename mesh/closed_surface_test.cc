#include "mesh/closed_surface.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>

namespace facets {
namespace {

Ellipsoid Tilted() {
  Ellipsoid e;
  e.centre = Eigen::Vector3d(1.0, -2.0, 0.5);
  e.axes = Eigen::AngleAxisd(0.4, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  e.radii = Eigen::Vector3d(0.6, 0.5, 0.4);
  return e;
}

TEST(ClosedSurface, EllipsoidMeshIsClosedEvenAndOnTheEllipsoid) {
  const Ellipsoid e = Tilted();
  const double edge = 0.05;
  const TinMesh mesh = MakeEllipsoidMesh(e, edge);
  const int n = static_cast<int>(std::lround(1.0515 * e.MeanRadius() / edge));  // 11
  EXPECT_EQ(mesh.n_faces(), 20u * n * n);
  EXPECT_EQ(mesh.n_vertices(), 10u * n * n + 2);
  double worst = 0.0;
  for (auto vh : mesh.vertices()) {
    const Eigen::Vector3d local =
        e.axes.transpose() * (ToEigen(mesh.point(vh)) - e.centre);
    worst = std::max(worst, std::abs(local.cwiseQuotient(e.radii).norm() - 1.0));
    // Normals point out of the ellipsoid.
    EXPECT_GT(ToEigen(mesh.normal(vh)).dot(ToEigen(mesh.point(vh)) - e.centre), 0.0);
  }
  EXPECT_LT(worst, 1e-12);
  double shortest = 1e9, longest = 0.0;
  for (auto eh : mesh.edges()) {
    const double l = mesh.calc_edge_length(eh);
    shortest = std::min(shortest, l);
    longest = std::max(longest, l);
  }
  EXPECT_GT(shortest, 0.5 * edge);
  EXPECT_LT(longest, 1.8 * edge);
  const ClosedSurfaceCheck check = CheckClosedSurface(mesh);
  EXPECT_TRUE(check.closed) << check.Brief();
  EXPECT_FALSE(check.self_intersecting) << check.Brief();
  // Volume 4/3 pi abc within the polyhedral approximation's deficit.
  const double volume = 4.0 / 3.0 * M_PI * 0.6 * 0.5 * 0.4;
  EXPECT_GT(check.volume, 0.98 * volume);
  EXPECT_LT(check.volume, volume);
}

TEST(ClosedSurface, FindsHolesAndSelfIntersections) {
  const TinMesh mesh = MakeEllipsoidMesh(Tilted(), 0.1);
  std::vector<Eigen::Vector3d> points;
  std::vector<Eigen::Vector3i> triangles;
  TinPointsAndTriangles(mesh, &points, &triangles);
  // One triangle missing: a hole of 3 border edges.
  std::vector<Eigen::Vector3i> holed(triangles.begin() + 1, triangles.end());
  const ClosedSurfaceCheck hole = CheckClosedSurface(points, holed);
  EXPECT_FALSE(hole.closed);
  EXPECT_EQ(hole.border_edges, 3);
  EXPECT_FALSE(hole.self_intersecting);
  // One vertex pushed through the opposite side.
  std::vector<Eigen::Vector3d> pushed = points;
  pushed[0] = Tilted().centre - 1.5 * (points[0] - Tilted().centre);
  EXPECT_TRUE(CheckClosedSurface(pushed, triangles).self_intersecting);
  // Duplicated points (a tessellation split along a crease) are merged, not a hole.
  std::vector<Eigen::Vector3d> doubled = points;
  std::vector<Eigen::Vector3i> split = triangles;
  doubled.push_back(points[split[0][0]]);
  split[0][0] = static_cast<int>(doubled.size()) - 1;
  const ClosedSurfaceCheck merged = CheckClosedSurface(doubled, split);
  EXPECT_TRUE(merged.closed) << merged.Brief();
  EXPECT_EQ(merged.vertices, static_cast<int>(points.size()));
}

TEST(ClosedSurface, HullMeshLiesOnTheInflatedHull) {
  // Points inside and on a 0.4 x 0.2 x 0.1 box: the hull is the box.
  std::vector<Eigen::Vector3d> points;
  for (int i = 0; i <= 4; ++i) {
    for (int j = 0; j <= 4; ++j) {
      for (int k = 0; k <= 4; ++k) points.emplace_back(0.1 * i, 0.05 * j, 0.025 * k);
    }
  }
  const Eigen::Vector3d centre(0.2, 0.1, 0.05);
  const TinMesh mesh = MakeHullMesh(points, centre, 0.03, 0.1);
  double worst = 0.0;
  for (auto vh : mesh.vertices()) {
    // On the box grown by 10 % about the centre: the largest scaled coordinate is 1.
    const Eigen::Vector3d d = (ToEigen(mesh.point(vh)) - centre).cwiseQuotient(Eigen::Vector3d(0.22, 0.11, 0.055));
    worst = std::max(worst, std::abs(d.cwiseAbs().maxCoeff() - 1.0));
  }
  EXPECT_LT(worst, 1e-9);
  const ClosedSurfaceCheck check = CheckClosedSurface(mesh);
  EXPECT_TRUE(check.closed) << check.Brief();
  EXPECT_FALSE(check.self_intersecting) << check.Brief();
  // Triangles spanning the box's edges and corners cut a little off.
  EXPECT_LE(check.volume, 0.44 * 0.22 * 0.11);
  EXPECT_GT(check.volume, 0.9 * 0.44 * 0.22 * 0.11);
  EXPECT_THROW(MakeHullMesh(points, Eigen::Vector3d(1.0, 0.0, 0.0), 0.03, 0.1), std::runtime_error);
}

TEST(ClosedSurface, TinFromTrianglesNamesTheSourceOfBadInput) {
  const std::vector<Eigen::Vector3d> points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  try {
    TinFromTriangles(points, {Eigen::Vector3i(0, 1, 5)}, "start.ply");
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("start.ply: triangle 0 refers to vertex 5"), std::string::npos)
        << e.what();
  }
  EXPECT_EQ(TinFromTriangles(points, {Eigen::Vector3i(0, 1, 2)}, "x").n_faces(), 1u);
}

}  // namespace
}  // namespace facets
