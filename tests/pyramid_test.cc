// Issue 6 acceptance, image pyramid: started 5 m below the truth, the run with the
// pyramid converges to the truth and the run without it converges wrongly or needs at
// least 5x more finest-level iterations (seed 001). Scene: the seed gable roof with a
// long-wave texture band the coarse levels can match (scenes/data/pyramid_gable.json;
// the seed's 2-4.8 m band alone is filtered away at the coarse levels, see
// docs/EXPERIMENTS.md).
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <random>

#include "scenes/albedo.h"
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
  const PyramidGable gable;
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

// The scene's second texture band adds its own waves and leaves the main band as it
// was (the seed scenes render byte-identical); a bad band names its JSON path.
TEST(Pyramid, ExtraAlbedoBandAddsToTheMainBand) {
  const Scene scene = LoadScene(std::string(FACETS_SOURCE_DIR) + "/scenes/data/pyramid_gable.json");
  ASSERT_EQ(scene.albedo.extra_bands.size(), 1u);
  AlbedoOptions main_only = scene.albedo;
  main_only.extra_bands.clear();
  AlbedoOptions silent = scene.albedo;
  silent.extra_bands[0].contrast = 0.0;
  const ProceduralAlbedo both(scene.albedo), main(main_only), zero(silent);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-50, 50);
  double sum = 0, sum_sq = 0;
  const int n = 4000;
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d p(u(rng), u(rng), 0.1 * u(rng));
    ASSERT_EQ(zero.Texture(p), main.Texture(p));
    const double d = both.Texture(p) - main.Texture(p);
    sum += d;
    sum_sq += d * d;
  }
  const double sd = std::sqrt(sum_sq / n - std::pow(sum / n, 2));
  EXPECT_NEAR(sd, scene.albedo.extra_bands[0].contrast, 0.04);  // 16 waves up to 20 m: a rough sample

  nlohmann::json j = scene.json;
  j["albedo"]["extra_bands"][0]["wavelength_max"] = 1.0;
  try {
    ParseScene(j, "pyramid_gable.json");
    FAIL() << "expected an error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("/albedo/extra_bands/0/wavelength_max"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace facets
