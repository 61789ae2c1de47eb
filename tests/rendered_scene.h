// Test helper: a bundled or test scene rendered into a folder and read back as the
// block a user would give `facets reconstruct` (COLMAP model + images), with the
// scene's window as region of interest.
#pragma once

#include <string>

#include "io/colmap_io.h"
#include "io/image_block.h"
#include "scenes/renderer.h"
#include "scenes/scene.h"

namespace facets {

struct RenderedScene {
  Scene scene;
  std::string dir;
  ImageBlock block;
};

// scene_file relative to the source tree, e.g. "scenes/data/seed_gable_parallel.json".
inline RenderedScene RenderAndRead(const std::string& scene_file, const std::string& dir) {
  RenderedScene r;
  r.scene = LoadScene(std::string(FACETS_SOURCE_DIR) + "/" + scene_file);
  r.dir = dir;
  RenderScene(r.scene, dir);
  r.block = ReadColmapModel(dir + "/sparse", dir + "/images");
  r.block.roi = r.scene.roi;
  return r;
}

}  // namespace facets
