// End-to-end: the reconstruction driver (pyramid, multigrid, start from the tie points)
// on the seed gable-roof pair, scored by the evaluation against the truth.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>

#include "engine/reconstruction.h"
#include "io/colmap_io.h"
#include "scenes/evaluate.h"
#include "scenes/renderer.h"
#include "scenes/scene.h"
#include "tests/rendered_scene.h"

namespace facets {
namespace {

// break_off_gsd: 0 = the metre bound of AdjustmentOptions (0.01 m doubled per level), else
// the bound in ground pixels of each level (what `facets reconstruct` uses by default).
void ReconstructSeedGable(double break_off_gsd, const std::string& name) {
  const RenderedScene rendered =
      RenderAndRead("scenes/data/seed_gable_parallel.json", testing::TempDir() + "/" + name);
  const std::string& dir = rendered.dir;
  ImageBlock block = rendered.block;  // the 24 m x 24 m window; start height from the tie points

  ReconstructionOptions options;
  options.levels = 3;
  // The plane start this test was written for: from the tie-point start the finest
  // level's first window oscillates (30 iterations, not converged) although its
  // result is closer to the truth (docs/EXPERIMENTS.md, tie-point start).
  options.start = StartSurfaceKind::kPlane;
  options.break_off_gsd = break_off_gsd;
  options.progress = [](const std::string& line) { std::cout << line << "\n"; };
  const Reconstruction r = Reconstruct(block, options);
  ASSERT_EQ(r.report.levels.size(), 3u);
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
  ReconstructSeedGable(0.0, "facets_reconstruct_seed_gable");
}

// The CLI's default: 0.06 ground pixel (0.0144 m on the seeds' finest level against
// 0.01 m) passes the same bounds.
TEST(Reconstruct, SeedGableRoofWithTheBreakOffInGroundPixels) {
  ReconstructSeedGable(0.06, "facets_reconstruct_seed_gable_gsd");
}

}  // namespace
}  // namespace facets
