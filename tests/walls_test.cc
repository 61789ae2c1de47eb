// Issue 7 guards: a block-scene reconstruction around the 10 x 10 x 4 m flat building,
// whose walls stand up out of the tie-point start, must come out free of
// self-intersections (CGAL's predicate on the output TIN and surface facets) with the fold guard and the
// wall passes on, and must flag the wall that only one image sees well. Small: 2
// levels, a 14 x 14 m region, one sweep.
#include <gtest/gtest.h>

#include <algorithm>
#include <iostream>

#include "engine/pipeline/reconstruction.h"
#include "engine/pipeline/scene_preset.h"
#include "mesh/closed_surface.h"
#include "refine/facet_crossings.h"
#include "mesh/surface_validity.h"
#include "scenes/evaluate.h"
#include "tests/rendered_scene.h"

namespace facets {
namespace {

double Median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

TEST(Walls, BlockBuildingIsValidAndFlagsTheWallOneImageSees) {
  const RenderedScene scene = RenderAndRead("scenes/data/block.json");
  // The aerial path (wall searches, V-cycle, corners, feet and eaves) on two levels.
  ReconstructionOptions options;
  ApplyScenePreset(ScenePreset::kAerial, &options);
  options.break_off_gsd = 0.0;  // the break-off in metres of AdjustmentOptions
  options.levels = 2;
  options.windows.sweeps = 1;
  options.adjustment.max_iterations = 10;
  RegionOfInterest roi;
  roi.min = Eigen::Vector3d(11, -23, -3);
  roi.max = Eigen::Vector3d(25, -9, 20);
  options.roi = roi;
  const Reconstruction r = Reconstruct(scene.block, options);
  ASSERT_EQ(r.report.levels.size(), 4u);  // the descent and the V-cycle, two levels each
  for (const LevelReport& level : r.report.levels) {
    std::cout << "level " << level.level << ": " << level.faces << " faces, sigma0 " << level.window.sigma0
              << ", " << level.folded_faces << " folded, "
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
  // The output surface (the facets surface.ply holds) too: crossing facets were pulled
  // toward their chords.
  std::cout << "surface facets: " << r.report.facet_crossings.Brief() << "\n";
  EXPECT_GE(r.report.facet_crossings.pairs_found, 0);
  EXPECT_EQ(r.report.facet_crossings.pairs_left, 0);
  EXPECT_EQ(CountCrossingFacets(r.tessellation), 0);
  // The walls did stand up: the finest TIN reaches the 4 m eaves.
  double top = -1e300;
  for (const auto& p : points) top = std::max(top, p.z());
  EXPECT_GT(top, 3.0);

  // Views. The south wall (y = -21) faces the southern oblique at 58 degrees and the
  // southern nadir row at 87 degrees (1-2 pixels of its height): one view. The north
  // (y = -11) and west (x = 13) walls face an oblique and a nadir row at 66-70 degrees.
  ASSERT_EQ(r.vertex_views.size(), r.mesh.n_vertices());
  int south = 0, south_flagged = 0, seen = 0, seen_flagged = 0;
  std::vector<double> sigma_flagged, sigma_three;
  for (auto vh : r.mesh.vertices()) {
    const auto p = r.mesh.point(vh);
    if (p[2] < 0.7 || p[2] > 3.3) continue;
    const bool flagged = r.vertex_flags[vh.idx()] & kVertexFewViews;
    const bool on_south = std::abs(p[1] + 21) < 0.8 && p[0] > 13.8 && p[0] < 22.2;
    const bool on_seen = (std::abs(p[1] + 11) < 0.8 && p[0] > 13.8 && p[0] < 22.2) ||
                         (std::abs(p[0] - 13) < 0.8 && p[1] > -20.2 && p[1] < -11.8);
    if (!on_south && !on_seen) continue;
    south += on_south;
    south_flagged += on_south && flagged;
    seen += on_seen;
    seen_flagged += on_seen && flagged;
    if (flagged) sigma_flagged.push_back(r.vertex_sigma[vh.idx()]);
    if (r.vertex_views[vh.idx()] >= 3) sigma_three.push_back(r.vertex_sigma[vh.idx()]);
  }
  std::cout << "south wall: " << south_flagged << " of " << south << " vertices flagged; north and west walls: "
            << seen_flagged << " of " << seen << "; sigma median flagged " << Median(sigma_flagged) << " m ("
            << sigma_flagged.size() << "), >= 3 views " << Median(sigma_three) << " m (" << sigma_three.size()
            << ")\n";
  ASSERT_GT(south, 3);
  ASSERT_GT(seen, 6);
  // Vertices near the south wall's eave and foot are also seen by the views of the roof
  // and the ground: a third of the band at least, against under a quarter elsewhere.
  EXPECT_GT(south_flagged, south / 3);
  EXPECT_LT(seen_flagged, seen / 4);
  EXPECT_GT(Median(sigma_flagged), Median(sigma_three));
}

// The search along the normals between levels (issue 7, engine/normal_search.h) and the
// plane propagation after it (engine/plane_propagation.h) on the block's tall building
// (20 x 12 x 12 m, 4 levels, the whole pipeline): walls that two or more images see come
// out far more complete at 1 ground pixel than without them (82.0 % with both, 68.5 %
// with the search alone, 36.3 % with neither, session 13; the runs do not depend on the
// thread count), and the surface stays free of crossings. Rounds on level 0 as well, kept
// whatever sigma0 does (`--normal-search-rounds-last-level 0 --normal-search-tolerance 1`),
// stand more of them up (87.9 % against 82.0 %; before the propagation 79.7 against 68.5 %).
// Session 29 (folding straightening vertices left off, folded lip rims flattened): 91.4 % with
// both, 65.5 % without the propagation, 45.9 % with neither, 93.4 % with the rounds; the rounds'
// gain shrank to +2 points because the run without them improved, so the rounds are held to an
// absolute bound and to not losing walls rather than to a fixed gain.
TEST(Walls, NormalSearchStandsTheTallBuildingsWallsUp) {
  const RenderedScene scene = RenderAndRead("scenes/data/block.json");
  RegionOfInterest roi;
  roi.min = Eigen::Vector3d(-30, -30, -3);
  roi.max = Eigen::Vector3d(-2, -6, 20);
  const TruthScene truth = ReadTruthScene(scene.dir);
  struct Run {
    double walls = -1.0;  // wall truth seen by >= 2 images within 1 ground pixel
    int crossing = -1;
    int finest_rounds = -1;  // normal-search rounds kept on level 0
  };
  auto run = [&](bool search, bool finest_rounds, bool planes = true) {
    ReconstructionOptions options;
    options.break_off_gsd = 0.0;  // the break-off in metres of AdjustmentOptions
    options.levels = 4;
    options.roi = roi;
    options.normal_search = search;
    options.plane_propagation = planes;
    if (finest_rounds) {
      options.normal_search_rounds_last_level = 0;
      options.normal_search_tolerance = 1.0;
    }
    const Reconstruction r = Reconstruct(scene.block, options);
    Run result;
    result.crossing = r.report.levels.back().self_intersections;
    result.finest_rounds = r.report.levels.back().normal_search_rounds;
    MeshData surface;
    surface.vertices = r.tessellation.points;
    surface.faces = r.tessellation.triangles;
    EvaluationOptions evaluation;
    evaluation.roi = roi;
    const EvaluationReport report = Evaluate(truth, surface, evaluation);
    const RegionScore* wall = report.Region("wall");
    if (wall != nullptr && wall->multi_view.within.size() >= 2) result.walls = wall->multi_view.within[1];
    return result;
  };
  const Run with = run(true, false);
  const Run without = run(false, false);
  const Run rounds = run(true, true);
  const Run no_planes = run(true, false, false);
  std::cout << "walls >= 2 views within 1 GSD: " << with.walls << " with the normal search and plane propagation, "
            << no_planes.walls << " without the propagation, " << without.walls << " without either, "
            << rounds.walls << " with rounds on level 0 (" << rounds.finest_rounds << " kept); crossing pairs "
            << with.crossing << " / " << no_planes.crossing << " / " << without.crossing << " / " << rounds.crossing
            << "\n";
  EXPECT_GT(with.walls, 0.85);
  EXPECT_GT(with.walls, without.walls + 0.2);
  EXPECT_EQ(with.crossing, 0);
  EXPECT_EQ(with.finest_rounds, 0);
  EXPECT_EQ(rounds.finest_rounds, 2);
  EXPECT_GT(rounds.walls, 0.9);
  EXPECT_GT(rounds.walls, with.walls);
  EXPECT_EQ(rounds.crossing, 0);
  // Plane propagation (engine/plane_propagation.h, default since session 13).
  EXPECT_GT(with.walls, no_planes.walls + 0.07);
}

}  // namespace
}  // namespace facets
