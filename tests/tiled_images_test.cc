// Level images read per window from tiled files (engine/level_image_store.h) give the
// same reconstruction as level images held in memory, and the tiled files are gone
// afterwards.
#include <gtest/gtest.h>

#include <filesystem>

#include "engine/pipeline/reconstruction.h"
#include "io/colmap_io.h"
#include "scenes/renderer.h"
#include "scenes/scene.h"
#include "tests/rendered_scene.h"

namespace facets {
namespace {

TEST(TiledImages, SameSurfaceAsImagesInMemory) {
  const RenderedScene rendered =
      RenderAndRead("scenes/data/seed_gable_parallel.json");
  ImageBlock block = rendered.block;
  ReconstructionOptions options;
  options.break_off_gsd = 0.0;  // the break-off in metres of AdjustmentOptions
  options.levels = 3;
  options.windows.partition.max_faces = 100;  // several windows, each with its own regions
  const Reconstruction memory = Reconstruct(block, options);
  const std::string cache = testing::TempDir() + "/facets_tiled_images_cache";
  options.image_cache_dir = cache;
  options.image_cache_mb = 8.0;
  const Reconstruction tiled = Reconstruct(block, options);
  EXPECT_FALSE(memory.report.images_cached);
  EXPECT_TRUE(tiled.report.images_cached);
  ASSERT_EQ(memory.mesh.n_vertices(), tiled.mesh.n_vertices());
  double worst = 0.0;
  for (auto vh : memory.mesh.vertices()) {
    worst = std::max(worst, (memory.mesh.point(vh) - tiled.mesh.point(vh)).norm());
  }
  std::cout << "tiled vs memory: " << memory.mesh.n_vertices() << " vertices, largest difference "
            << worst << " m; level 0 windows " << tiled.report.levels.back().windows.size() << "\n";
  EXPECT_LT(worst, 1e-6);
  EXPECT_GT(tiled.report.levels.back().windows.size(), 1u);
  EXPECT_NEAR(memory.report.levels.back().window.sigma0, tiled.report.levels.back().window.sigma0, 1e-6);
  EXPECT_FALSE(std::filesystem::exists(cache));
}

}  // namespace
}  // namespace facets
