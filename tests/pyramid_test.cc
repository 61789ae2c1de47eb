// Issue 6 acceptance, image pyramid: started 5 m below the truth, the run with the
// pyramid converges to the truth and the run without it converges wrongly or needs at
// least 5x more finest-level iterations (seed 001). Scene: the seed gable roof with a
// long-wave texture band the coarse levels can match (scenes/data/pyramid_gable.json;
// the seed's 2-4.8 m band alone is filtered away at the coarse levels, see
// docs/EXPERIMENTS.md).
#include <gtest/gtest.h>

#include <iostream>

#include "tests/pyramid_gable.h"

namespace facets {
namespace {

int FinestIterations(const Reconstruction& r) {
  int iterations = 0;
  for (const auto& window : r.report.levels.back().windows) {
    iterations = std::max(iterations, static_cast<int>(window.iterations.size()));
  }
  return iterations;
}

TEST(Pyramid, FiveMetresBelowConvergesOnlyWithThePyramid) {
  const PyramidGable gable(testing::TempDir() + "/facets_pyramid_gable");
  const double start = gable.true_mean_height - 5.0;
  const Reconstruction with = Reconstruct(gable.block, PyramidGableOptions(3, start));
  const Reconstruction without = Reconstruct(gable.block, PyramidGableOptions(1, start));
  const HeightErrors e3 = gable.Heights(with);
  const HeightErrors e1 = gable.Heights(without);
  std::cout << "true mean height " << gable.true_mean_height << " m, start " << start << " m\n"
            << "3 levels: " << with.report.BriefReport() << "\n  rms " << e3.rms << " m, finest "
            << FinestIterations(with) << " iterations\n"
            << "1 level:  " << without.report.BriefReport() << "\n  rms " << e1.rms << " m, finest "
            << FinestIterations(without) << " iterations\n";
  // Measured: 0.060 m (the seed's Table 4.1 gives 0.063 m for this roof), sigma0 3.96.
  EXPECT_LT(e3.rms, 0.10);
  EXPECT_EQ(e3.missing, 0u);
  EXPECT_NEAR(with.report.levels.back().window.sigma0, 4.0, 0.4);
  // Measured: 3.88 m, sigma0 10.2 after 60 iterations.
  const bool wrong = e1.rms > 1.0;
  const bool slow = FinestIterations(without) >= 5 * FinestIterations(with);
  EXPECT_TRUE(wrong || slow) << "without the pyramid: rms " << e1.rms << " m, "
                             << FinestIterations(without) << " iterations";
}

}  // namespace
}  // namespace facets
