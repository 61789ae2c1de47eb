#include "engine/images/level_images.h"

namespace facets {

void LoadLevelImages(const ImageBlock& block, bool grey, LoadedImages* out) {
  out->planes.clear();
  out->images.clear();
  out->planes.reserve(block.images.size());  // LevelImage points into it: no reallocation
  for (const auto& image : block.images) {
    ImagePlanes planes = ReadImageFor(image.path, block.CameraOf(image));
    out->planes.push_back(grey ? planes.Grey() : std::move(planes));
  }
  for (size_t k = 0; k < block.images.size(); ++k) {
    out->images.push_back({block.images[k].image_id, &block.CameraOf(block.images[k]),
                           block.images[k].cam_from_world, &out->planes[k]});
  }
}

}  // namespace facets
