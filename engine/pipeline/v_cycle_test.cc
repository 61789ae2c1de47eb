// Going back up the pyramid (engine/v_cycle.h): a coarse TIN's vertices move along their
// normals onto a finer surface, the nearer side wins, and what the surface does not
// reach within the distance stays.
#include "engine/pipeline/v_cycle.h"

#include <gtest/gtest.h>

#include <cmath>

namespace facets {
namespace {

// A 10 x 10 m grid at z = 0, 1 m spacing, normals up.
TinMesh FlatGrid() {
  StartGridOptions grid;
  grid.min = Eigen::Vector2d(0, 0);
  grid.max = Eigen::Vector2d(10, 10);
  grid.spacing = 1.0;
  TinMesh mesh = MakeStartGrid(grid);
  UpdateVertexNormals(&mesh);
  return mesh;
}

// Two triangles of the plane z = height over [x0, x1] x [0, 10].
Tessellation Plane(double height, double x0, double x1) {
  Tessellation surface;
  surface.points = {{x0, -1, height}, {x1, -1, height}, {x1, 11, height}, {x0, 11, height}};
  surface.triangles = {{0, 1, 2}, {0, 2, 3}};
  return surface;
}

TEST(VCycle, VerticesMoveAlongTheirNormalsOntoTheSurfaceAboveOrBelow) {
  for (double height : {0.3, -0.4}) {
    TinMesh mesh = FlatGrid();
    const ProjectionReport report = ProjectAlongNormals(&mesh, Plane(height, -1, 11), 1.0);
    EXPECT_EQ(report.moved, static_cast<int>(mesh.n_vertices()));
    EXPECT_EQ(report.missed, 0);
    EXPECT_NEAR(report.median_move, std::abs(height), 1e-5);
    for (auto vh : mesh.vertices()) EXPECT_NEAR(mesh.point(vh)[2], height, 1e-5);
  }
}

TEST(VCycle, VerticesTheSurfaceDoesNotReachStay) {
  TinMesh mesh = FlatGrid();
  // Too far: nothing moves.
  ProjectionReport report = ProjectAlongNormals(&mesh, Plane(0.5, -1, 11), 0.4);
  EXPECT_EQ(report.moved, 0);
  EXPECT_EQ(report.missed, static_cast<int>(mesh.n_vertices()));
  // Only over x in [-1, 4.5]: the columns x = 0..4 move, x = 5..10 stay.
  report = ProjectAlongNormals(&mesh, Plane(0.2, -1, 4.5), 1.0);
  EXPECT_EQ(report.moved, 5 * 11);
  EXPECT_EQ(report.missed, 6 * 11);
  for (auto vh : mesh.vertices()) {
    const auto p = mesh.point(vh);
    EXPECT_NEAR(p[2], p[0] < 4.5 ? 0.2 : 0.0, 1e-5) << p[0] << " " << p[1];
  }
}

}  // namespace
}  // namespace facets
