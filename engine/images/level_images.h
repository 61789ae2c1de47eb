// The images of a block, loaded and wrapped as the adjustment's LevelImages.
#pragma once

#include <vector>

#include "engine/images/level_image.h"
#include "io/image_block.h"

namespace facets {

// Owns the pixels; `images` points into `planes` and into the block's cameras, so
// the block must outlive it and it must not be copied after loading.
struct LoadedImages {
  std::vector<ImagePlanes> planes;
  std::vector<LevelImage> images;

  LoadedImages() = default;
  LoadedImages(const LoadedImages&) = delete;
  LoadedImages& operator=(const LoadedImages&) = delete;
};

// Reads every image of the block (errors name the file: missing, unreadable, size
// differing from its camera); grey = true averages the channels into one.
void LoadLevelImages(const ImageBlock& block, bool grey, LoadedImages* out);

}  // namespace facets
