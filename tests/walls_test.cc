// Issue 7 guards: a block-scene reconstruction around the 10 x 10 x 4 m flat building,
// whose walls stand up out of the tie-point start, must come out free of
// self-intersections (CGAL's predicate on the output TIN) with the fold guard and the
// wall passes on. Small: 2 levels, a 14 x 14 m region, one sweep.
#include <gtest/gtest.h>

#include <iostream>

#include "engine/reconstruction.h"
#include "mesh/closed_surface.h"
#include "mesh/surface_validity.h"
#include "tests/rendered_scene.h"

namespace facets {
namespace {

TEST(Walls, BlockBuildingHasNoSelfIntersections) {
  const RenderedScene scene = RenderAndRead("scenes/data/block.json", testing::TempDir() + "/facets_walls_block");
  ReconstructionOptions options;
  options.levels = 2;
  options.wall_passes = 1;
  options.windows.sweeps = 1;
  options.adjustment.max_iterations = 10;
  RegionOfInterest roi;
  roi.min = Eigen::Vector3d(11, -23, -3);
  roi.max = Eigen::Vector3d(25, -9, 20);
  options.roi = roi;
  const Reconstruction r = Reconstruct(scene.block, options);
  ASSERT_EQ(r.report.levels.size(), 2u);
  for (const LevelReport& level : r.report.levels) {
    std::cout << "level " << level.level << ": " << level.faces << " faces, sigma0 " << level.window.sigma0
              << ", " << level.wall_passes.size() << " wall passes, " << level.folded_faces << " folded, "
              << level.self_intersections << " self-intersecting pairs, " << level.fold_limited
              << " steps limited\n";
  }
  std::vector<Eigen::Vector3d> points;
  std::vector<Eigen::Vector3i> triangles;
  TinPointsAndTriangles(r.mesh, &points, &triangles);
  const ClosedSurfaceCheck check = CheckClosedSurface(points, triangles, 0.0);
  std::cout << check.Brief() << "\n";
  EXPECT_GT(check.border_edges, 0);  // an open TIN over the region, valid as a polygon mesh
  EXPECT_FALSE(check.self_intersecting);
  EXPECT_EQ(CountSelfIntersections(r.mesh), 0);
  EXPECT_EQ(r.report.levels.back().self_intersections, 0);
  // The walls did stand up: the finest TIN reaches the 4 m eaves.
  double top = -1e300;
  for (const auto& p : points) top = std::max(top, p.z());
  EXPECT_GT(top, 3.0);
}

}  // namespace
}  // namespace facets
