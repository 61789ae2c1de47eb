// Rendering speed of the synthetic-scene renderer: one 1000 x 750 image of the block
// scene (first nadir image and first oblique), S x S supersampling, all TBB threads.
//
//   build/scenes/facets_render_bench [scene.json] [repetitions]
#include <tbb/info.h>

#include <algorithm>
#include <chrono>
#include <ctime>
#include <cstdio>
#include <string>

#include "scenes/camera_layout.h"
#include "scenes/renderer.h"

int main(int argc, char** argv) {
  using namespace facets;
  const std::string path =
      argc > 1 ? argv[1] : std::string(FACETS_SOURCE_DIR) + "/scenes/data/block.json";
  const int reps = argc > 2 ? std::stoi(argv[2]) : 3;
  const Scene scene = LoadScene(path);
  auto t0 = std::chrono::steady_clock::now();
  const TruthMesh mesh = BuildTruthMesh(scene);
  const ImageBlock block = BuildImageBlock(scene);
  const Renderer renderer(scene, mesh);
  const double setup =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("scene %s: %zu triangles, setup (mesh + BVH) %.3f s, %d threads\n",
              scene.name.c_str(), mesh.faces.size(), setup,
              tbb::info::default_concurrency());
  const size_t oblique = std::min<size_t>(block.images.size() - 1, 9);
  for (size_t index : {size_t{0}, oblique}) {
    const BlockImage& image = block.images[index];
    const Camera& camera = block.CameraOf(image);
    for (int s : {1, scene.supersampling}) {
      double best = 1e300, cpu = 1e300;
      for (int r = 0; r < reps; ++r) {
        t0 = std::chrono::steady_clock::now();
        const std::clock_t c0 = std::clock();
        const auto clean = renderer.RenderClean(camera, image, s);
        const auto grey = AddNoiseAndQuantise(clean, scene.noise_sigma, 1);
        best = std::min(best, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
        cpu = std::min(cpu, double(std::clock() - c0) / CLOCKS_PER_SEC);
      }
      const double rays = double(camera.width) * camera.height * s * s;
      // CPU time is reported too: on a shared machine the wall time depends on the load.
      std::printf("%s %dx%d S=%d: wall %.3f s (best of %d), CPU %.3f s, %.2f Mrays/s wall\n",
                  image.name.c_str(), camera.width, camera.height, s, best, reps, cpu,
                  rays / best * 1e-6);
    }
  }
  return 0;
}
