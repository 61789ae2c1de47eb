// One image on one pyramid level as the windows, the searches and the start surfaces
// read it: camera scaled to the level, pose, pixels, and its foreground outline.
#pragma once

#include "io/camera.h"
#include "io/image_io.h"
#include "io/rigid3d.h"
#include "visibility/silhouette.h"

namespace facets {

// One image as the adjustment sees it on one level. The pointers are not owned and
// must outlive the adjustment.
struct LevelImage {
  int image_id = 0;
  const Camera* camera = nullptr;      // scaled to the level
  Rigid3d cam_from_world;
  const ImagePlanes* pixels = nullptr;  // same channel count for every image
  // The image's foreground outline (AdjustmentOptions::silhouette_weight); null: none.
  const SilhouetteView* silhouette = nullptr;
};

}  // namespace facets
