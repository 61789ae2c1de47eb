// Engine core benchmark: observations (pixels) linearised and accumulated into the
// normal equations per second per core, and the time split of one iteration.
//
//   facets_engine_bench [RENDERED_BLOCK_DIR]
// Renders scenes/data/block.json into a temporary folder unless a rendered one is
// given, starts a 48 m x 48 m window on a plane at the mean terrain height, and runs
// two iterations with 1 and with 2 threads.
#include <tbb/global_control.h>

#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "engine/images/level_images.h"
#include "engine/solver/window_adjustment.h"
#include "io/colmap_io.h"
#include "io/image_io.h"
#include "mesh/tin.h"
#include "scenes/renderer.h"
#include "scenes/scene.h"

using namespace facets;

int main(int argc, char** argv) {
  std::string dir = argc > 1 ? argv[1] : "";
  const Scene scene = LoadScene(std::string(FACETS_SOURCE_DIR) + "/scenes/data/block.json");
  if (dir.empty()) {
    dir = (std::filesystem::temp_directory_path() / "facets_engine_bench_block").string();
    RenderScene(scene, dir);
  }
  const ImageBlock block = ReadColmapModel(dir + "/sparse", dir + "/images");
  LoadedImages loaded;
  LoadLevelImages(block, /*grey=*/true, &loaded);
  const std::vector<LevelImage>& images = loaded.images;
  std::printf("block: %zu images; ground pixel %.3f m\n", images.size(), scene.ground_pixel_size);
  for (int threads : {1, 2}) {
    tbb::global_control control(tbb::global_control::max_allowed_parallelism, threads);
    StartGridOptions grid;
    grid.min = Eigen::Vector2d(-24, -24);
    grid.max = Eigen::Vector2d(24, 24);
    grid.spacing = 8 * scene.ground_pixel_size;  // 4x4 facets of 2x2 pixels
    grid.plane_height = scene.mean_terrain_height;
    TinMesh mesh = MakeStartGrid(grid);
    AdjustmentOptions options;
    options.max_iterations = 2;
    options.compute_precision = false;
    WindowAdjustment adjustment(&mesh, images, options);
    const WindowReport report = adjustment.Run();
    std::printf("\n%d thread(s): %zu vertices, %zu faces, %d unknowns\n", threads, mesh.n_vertices(),
                mesh.n_faces(), report.unknowns);
    std::printf("  it  observations  cast[s]  linearise+assemble[s]  solve[s] (CG it)  update[s]  Mobs/s/core\n");
    for (const auto& it : report.iterations) {
      std::printf("  %2d  %12lld  %7.3f  %21.3f  %8.3f (%4d)  %9.3f  %11.2f\n", it.iteration,
                  it.observations, it.seconds_cast, it.seconds_linearise, it.seconds_solve,
                  it.cg_iterations, it.seconds_update,
                  it.observations / it.seconds_linearise / threads * 1e-6);
    }
  }
  return 0;
}
