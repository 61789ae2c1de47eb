// End-to-end: the reconstruction driver (pyramid, multigrid, start from the tie points)
// on the seed gable-roof pair, scored by the evaluation against the truth.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <stdexcept>
#include <utility>
#include <vector>

#include "engine/images/level_image_store.h"
#include "engine/pipeline/reconstruction.h"
#include "io/colmap_io.h"
#include "scenes/evaluate.h"
#include "scenes/renderer.h"
#include "scenes/scene.h"
#include "tests/rendered_scene.h"

namespace facets {
namespace {

// break_off_gsd: 0 = the metre bound of AdjustmentOptions (0.01 m doubled per level), else
// the bound in ground pixels of each level (what `facets reconstruct` uses by default).
void ReconstructSeedGable(double break_off_gsd) {
  const RenderedScene rendered =
      RenderAndRead("scenes/data/seed_gable_parallel.json");
  const std::string& dir = rendered.dir;
  ImageBlock block = rendered.block;  // the 24 m x 24 m window; start height from the tie points

  ReconstructionOptions options;
  options.break_off_gsd = 0.0;  // the break-off in metres of AdjustmentOptions
  options.levels = 3;
  // The plane start this test was written for: from the tie-point start the finest
  // level's first window oscillates (30 iterations, not converged) although its
  // result is closer to the truth (docs/EXPERIMENTS.md, tie-point start).
  options.start = StartSurfaceKind::kPlane;
  options.break_off_gsd = break_off_gsd;
  options.progress = [](const std::string& line) { std::cout << line << "\n"; };
  // level_done (`facets reconstruct --keep-levels`) sees every level's finished TIN.
  std::vector<std::pair<int, int>> levels_done;  // level, faces
  options.level_done = [&](int level, const TinMesh& mesh) {
    levels_done.emplace_back(level, static_cast<int>(mesh.n_faces()));
  };
  const Reconstruction r = Reconstruct(block, options);
  ASSERT_EQ(r.report.levels.size(), 3u);
  ASSERT_EQ(levels_done.size(), 3u);
  for (size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(levels_done[i].first, 2 - static_cast<int>(i));
    EXPECT_EQ(levels_done[i].second, r.report.levels[i].faces);
  }
  EXPECT_EQ(levels_done.back().second, static_cast<int>(r.mesh.n_faces()));
  for (const LevelReport& level : r.report.levels) {
    const double expected = break_off_gsd > 0 ? break_off_gsd * level.ground_pixel
                                              : 0.01 * std::pow(2.0, level.level);
    EXPECT_NEAR(level.break_off, expected, 1e-12) << "level " << level.level;
  }
  // Every finest window stops by the break-off or by the stall rule, none at the
  // iteration cap. Since rounded ridges are found (docs/ENGINE.md, Creases) the fit is
  // much closer (sigma0 4.1-4.2 against 4.4-5.0), but in one of the four windows a
  // ridge vertex keeps moving by 0.06-0.10 m per iteration at constant sigma0 and the
  // stall rule stops it (docs/EXPERIMENTS.md, seed 000).
  const LevelReport& finest_level = r.report.levels.back();
  for (const WindowReport& w : finest_level.windows) {
    EXPECT_TRUE(w.converged || w.stalled);
    EXPECT_LT(w.iterations.size(), static_cast<size_t>(AdjustmentOptions().max_iterations));
  }
  EXPECT_LT(finest_level.window.sigma0, 4.5);

  MeshData surface;
  surface.vertices = r.tessellation.points;
  surface.faces = r.tessellation.triangles;
  const EvaluationReport score = Evaluate(ReadTruthScene(dir), surface);
  const RegionScore* roof = score.Region("roof");
  ASSERT_NE(roof, nullptr);
  std::cout << score.Table();
  EXPECT_LT(roof->accuracy.median, 0.05);
  EXPECT_GT(roof->completeness.within[1], 0.85);  // within 1 ground pixel
}

TEST(Reconstruct, SeedGableRoofFromTiePointsWithPyramid) {
  ReconstructSeedGable(0.0);
}

// The CLI's default: 0.06 ground pixel (0.0144 m on the seeds' finest level against
// 0.01 m) passes the same bounds.
TEST(Reconstruct, SeedGableRoofWithTheBreakOffInGroundPixels) {
  ReconstructSeedGable(0.06);
}

// ReconstructionOptions::start_step_cap_pixels (`--start-step-cap`): with the tie-point
// start no node of the coarsest level ends further than the cap from where the start put
// it. The start is read from a run with a vanishing cap; the capped run's nodes all lie
// within the cap of it, some of them on it, and without a cap some lie beyond.
TEST(Reconstruct, CoarsestLevelStepsStayWithinTheCapOfTheTiePointStart) {
  const RenderedScene rendered =
      RenderAndRead("scenes/data/seed_gable_parallel.json");
  auto coarsest_tin = [&](double cap_pixels, double* ground_pixel) {
    ReconstructionOptions options;
    options.break_off_gsd = 0.0;  // the break-off in metres of AdjustmentOptions
    options.levels = 3;
    options.finest_level = 1;
    options.start_step_cap_pixels = cap_pixels;
    std::vector<Eigen::Vector3d> points;
    options.level_done = [&](int level, const TinMesh& mesh) {
      if (level != 2) return;
      for (auto vh : mesh.vertices()) points.push_back(ToEigen(mesh.point(vh)));
    };
    const Reconstruction r = Reconstruct(rendered.block, options);
    EXPECT_EQ(r.report.start_surface, "tiepoints");
    *ground_pixel = r.report.levels.front().ground_pixel;
    return points;
  };
  double pixel = 0.0;
  const std::vector<Eigen::Vector3d> start = coarsest_tin(1e-9, &pixel);
  const double cap = 0.25;  // level pixels
  const std::vector<Eigen::Vector3d> capped = coarsest_tin(cap, &pixel);
  const std::vector<Eigen::Vector3d> free = coarsest_tin(0.0, &pixel);
  ASSERT_EQ(capped.size(), start.size());
  ASSERT_EQ(free.size(), start.size());
  double capped_max = 0.0, free_max = 0.0;
  int on_cap = 0;
  for (size_t v = 0; v < start.size(); ++v) {
    const double d = (capped[v] - start[v]).norm();
    capped_max = std::max(capped_max, d);
    on_cap += d > 0.999 * cap * pixel;
    free_max = std::max(free_max, (free[v] - start[v]).norm());
  }
  std::cout << start.size() << " coarsest nodes, level pixel " << pixel << " m: capped run at most " << capped_max
            << " m from the start (" << on_cap << " on the cap), uncapped " << free_max << " m\n";
  EXPECT_LE(capped_max, cap * pixel * (1 + 1e-9));
  EXPECT_GT(on_cap, 0);
  EXPECT_GT(free_max, cap * pixel);
}

// ReconstructionOptions::finest_level (`facets reconstruct --finest-level`): 3 pyramid
// levels adjusted down to level 1 only. The products come from level 1: the seeds'
// ground pixel (0.24 m on the original images) doubled, TIN edges of 4 facets of 2
// level pixels, precision for every vertex; the roof fits within a tenth of a level-1
// ground pixel; the finer images are not kept.
TEST(Reconstruct, StopsAtACoarserFinestLevel) {
  const RenderedScene rendered =
      RenderAndRead("scenes/data/seed_gable_parallel.json");
  ReconstructionOptions options;
  options.break_off_gsd = 0.0;  // the break-off in metres of AdjustmentOptions
  options.levels = 3;
  options.finest_level = 1;
  options.start = StartSurfaceKind::kPlane;
  options.break_off_gsd = 0.06;
  options.progress = [](const std::string& line) { std::cout << line << "\n"; };
  const Reconstruction r = Reconstruct(rendered.block, options);
  ASSERT_EQ(r.report.levels.size(), 2u);
  EXPECT_EQ(r.report.levels[0].level, 2);
  const LevelReport& finest = r.report.levels.back();
  EXPECT_EQ(finest.level, 1);
  // Ground pixel of the original images at the ROI centre, from the cameras.
  const Eigen::Vector3d centre = 0.5 * (rendered.block.roi->min + rendered.block.roi->max);
  std::vector<double> gsd;
  for (const auto& image : rendered.block.images) {
    const Camera& camera = rendered.block.CameraOf(image);
    Eigen::Vector3d at = centre;
    at.z() = r.report.start_height;
    gsd.push_back((at - image.ProjectionCentre()).norm() / (0.5 * (camera.FocalX() + camera.FocalY())));
  }
  std::sort(gsd.begin(), gsd.end());
  const double gsd0 = gsd[gsd.size() / 2];
  std::cout << "ground pixel of the images " << gsd0 << " m, finest level " << finest.ground_pixel << " m\n";
  EXPECT_NEAR(finest.ground_pixel, 2.0 * gsd0, 1e-9);
  EXPECT_NEAR(finest.edge_length, 2.0 * kSubdivisions * 2.0 * gsd0, 1e-9);
  // The TIN is the level-1 TIN: mean edge within 25 % of the target (the quality pass's band).
  double length = 0.0;
  for (auto eh : r.mesh.edges()) length += r.mesh.calc_edge_length(eh);
  const double mean_edge = length / static_cast<double>(r.mesh.n_edges());
  std::cout << "mean TIN edge " << mean_edge << " m, target " << finest.edge_length << " m, " << r.mesh.n_faces()
            << " faces; " << r.report.BriefReport() << "\n";
  EXPECT_NEAR(mean_edge, finest.edge_length, 0.25 * finest.edge_length);
  EXPECT_EQ(static_cast<int>(r.mesh.n_faces()), finest.faces);
  EXPECT_EQ(r.tessellation.NumFaces(), finest.faces);
  ASSERT_EQ(r.vertex_sigma.size(), r.mesh.n_vertices());
  int with_sigma = 0;
  for (double s : r.vertex_sigma) with_sigma += s > 0.0 && std::isfinite(s) ? 1 : 0;
  EXPECT_GT(with_sigma, 0.9 * r.mesh.n_vertices());
  EXPECT_LT(finest.window.sigma0, 4.5);

  MeshData surface;
  surface.vertices = r.tessellation.points;
  surface.faces = r.tessellation.triangles;
  const EvaluationReport score = Evaluate(ReadTruthScene(rendered.dir), surface);
  const RegionScore* roof = score.Region("roof");
  ASSERT_NE(roof, nullptr);
  std::cout << score.Table();
  // Measured: median 0.0155 m (0.03 level-1 ground pixels), 98.8 % within 0.245 m.
  EXPECT_LT(roof->accuracy.median, 0.1 * finest.ground_pixel);
  EXPECT_GT(roof->completeness.within[1], 0.85);

  // The level images kept from level 1 up: (1/4 + 1/16) / (1 + 1/4 + 1/16) of the pyramid
  // from level 0 (the level sizes round up; measured 0.2384).
  LevelImageStoreOptions all, from1;
  all.levels = from1.levels = 3;
  from1.first_level = 1;
  const LevelImageStore store_all(rendered.block, all);
  const LevelImageStore store_from1(rendered.block, from1);
  EXPECT_NEAR(store_from1.MemoryMb() / store_all.MemoryMb(), 0.3125 / 1.3125, 0.002);
  ImageStorage storage;
  EXPECT_THROW(store_from1.Whole(0, &storage), std::logic_error);
  EXPECT_EQ(store_from1.Whole(1, &storage).size(), rendered.block.images.size());

  ReconstructionOptions bad = options;
  bad.finest_level = 3;
  EXPECT_THROW(bad.Check(), std::invalid_argument);
  bad = options;
  bad.straighten_tolerance = -0.01;
  EXPECT_THROW(bad.Check(), std::invalid_argument);
  bad.straighten_tolerance = 0.01;
  bad.straighten_local_rings = -2;
  EXPECT_THROW(bad.Check(), std::invalid_argument);
}

// Seed experiment 12: the gable ridge at 11.3 degrees to the grid, with the constant
// patch, curvature regularisation, lambda 2000. Without crease straightening the ridge
// is a zigzag of edges whose crease vertices spike (sigma0 4.53 in the seed table);
// with it a straight chain of vertices sits on the ridge (docs/ENGINE.md, Creases).
Reconstruction ReconstructRotatedGable(const RenderedScene& rendered, int straighten_rounds) {
  ReconstructionOptions options;
  options.break_off_gsd = 0.0;  // the break-off in metres of AdjustmentOptions
  options.levels = 3;
  options.start = StartSurfaceKind::kPlane;
  options.break_off_gsd = 0.06;
  options.adjustment.lambda = 2000.0;
  options.straighten_rounds = straighten_rounds;
  options.progress = [](const std::string& line) { std::cout << line << "\n"; };
  return Reconstruct(rendered.block, options);
}

TEST(Reconstruct, SkewRidgeIsStraightenedAndFitsWithinTheSeedRange) {
  const RenderedScene rendered = RenderAndRead("scenes/data/seed_gable_rotated_patch.json");
  const Reconstruction with = ReconstructRotatedGable(rendered, ReconstructionOptions().straighten_rounds);
  const Reconstruction without = ReconstructRotatedGable(rendered, 0);
  int kept = 0, moved = 0;
  for (const LevelReport& level : with.report.levels) {
    kept += level.straighten_kept;
    moved += level.straightened;
  }
  const double sigma_with = with.report.levels.back().window.sigma0;
  const double sigma_without = without.report.levels.back().window.sigma0;
  auto roof_p90 = [&](const Reconstruction& r) {
    MeshData surface;
    surface.vertices = r.tessellation.points;
    surface.faces = r.tessellation.triangles;
    const EvaluationReport score = Evaluate(ReadTruthScene(rendered.dir), surface);
    const RegionScore* roof = score.Region("roof");
    return roof ? roof->accuracy.p90 : 1e9;
  };
  const double p90_with = roof_p90(with), p90_without = roof_p90(without);
  std::cout << "skew ridge: " << kept << " straightening rounds kept, " << moved << " vertices moved; finest sigma0 "
            << sigma_with << " (without " << sigma_without << "), roof p90 " << p90_with << " m (without "
            << p90_without << " m)\n";
  // Measured (session 19, the windows around the moved vertices re-adjusted): 6 rounds
  // kept (3 on level 1, 3 on level 0), 78 vertex moves; sigma0 4.297 (without 4.518),
  // roof p90 0.055 m (without 0.077 m). With the whole level re-adjusted (before): 4.285,
  // 0.045 m. Session 24 (the same path since sessions 22-23 changed the levels): 4 rounds
  // kept, 54 moves, sigma0 4.304 (without 4.521), roof p90 0.059 m (without 0.076 m).
  EXPECT_GE(kept, 1);
  EXPECT_LE(sigma_with, 4.4);  // the seed's 4.2 within the acceptance range 3.8-4.4
  EXPECT_LT(sigma_with, sigma_without - 0.1);
  EXPECT_LT(p90_with, p90_without);
}

}  // namespace
}  // namespace facets
