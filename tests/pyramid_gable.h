// Test helper for the issue 6 pyramid and lifting acceptance: the pyramid scene
// (scenes/data/pyramid_gable.json) from the render cache (tests/rendered_scene.h), its block with the
// scene's window as ROI, the true mean height and the rms of true height errors.
#pragma once

#include <string>

#include "engine/pipeline/reconstruction.h"
#include "io/colmap_io.h"
#include "scenes/evaluate.h"
#include "scenes/renderer.h"
#include "scenes/scene.h"
#include "scenes/truth_mesh.h"
#include "tests/rendered_scene.h"
#include "tests/truth_start.h"

namespace facets {

struct PyramidGable {
  Scene scene;
  std::string dir;
  ImageBlock block;
  double true_mean_height = 0.0;  // of the highest surface over the ROI

  PyramidGable() {
    const std::string file = std::string(FACETS_SOURCE_DIR) + "/scenes/data/pyramid_gable.json";
    scene = LoadScene(file);
    dir = RenderSceneOnce(file, scene);
    block = ReadColmapModel(dir + "/sparse", dir + "/images");
    block.roi = scene.roi;
    const TruthMesh truth = BuildTruthMesh(scene);
    const Renderer renderer(scene, truth);
    double sum = 0.0;
    int count = 0;
    for (double x = scene.roi.min.x(); x <= scene.roi.max.x() + 1e-9; x += 0.5) {
      for (double y = scene.roi.min.y(); y <= scene.roi.max.y() + 1e-9; y += 0.5) {
        sum += TruthHeight(renderer, x, y);
        ++count;
      }
    }
    true_mean_height = sum / count;
  }

  // rms of the vertical differences on the grid `facets evaluate` uses (2 ground
  // pixels, 8 ground pixels of border left out).
  HeightErrors Heights(const Reconstruction& r) const {
    MeshData surface;
    surface.vertices = r.tessellation.points;
    surface.faces = r.tessellation.triangles;
    const double gsd = scene.ground_pixel_size;
    return EvaluateHeights(ReadTruthScene(dir).mesh, surface, scene.roi, 2 * gsd, 8 * gsd);
  }
};

// The options of the documented experiment (docs/EXPERIMENTS.md): adaptive
// regularisation, plane start at the given height.
inline ReconstructionOptions PyramidGableOptions(int levels, double start_height) {
  ReconstructionOptions options;
  options.break_off_gsd = 0.0;  // the break-off in metres of AdjustmentOptions
  options.levels = levels;
  options.adjustment.regularisation = RegularisationFromName("adaptive");
  options.start_height = start_height;
  return options;
}

}  // namespace facets
