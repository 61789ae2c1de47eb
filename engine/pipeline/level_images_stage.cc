#include "engine/pipeline/level_images_stage.h"

#include <tbb/parallel_for.h>

#include <chrono>

#include "engine/pipeline/reconstruction.h"
#include "engine/start/visual_hull.h"

namespace facets {
namespace {

LevelImageStoreOptions StoreOptions(const ReconstructionOptions& options) {
  LevelImageStoreOptions store;
  store.levels = options.levels;
  store.first_level = options.finest_level;
  store.filter = options.filter;
  store.colour = options.colour;
  if (options.image_cache_dir) {
    store.cache_dir = *options.image_cache_dir;
    store.cache_memory_mb = options.image_cache_mb;
  }
  return store;
}

// "stage images: reading N images, L pyramid levels[, adjusted down to level K]".
std::string ImagesLine(const ImageBlock& block, const ReconstructionOptions& options) {
  return "stage images: reading " + std::to_string(block.images.size()) + " images, " +
         std::to_string(options.levels) + " pyramid levels" +
         (options.finest_level > 0 ? ", adjusted down to level " + std::to_string(options.finest_level)
                                   : std::string());
}

}  // namespace

LevelImageSource::LevelImageSource(const ImageBlock& block, const ReconstructionOptions& options,
                                   const std::function<void(const std::string&)>& say)
    : started_((say(ImagesLine(block, options)), std::chrono::steady_clock::now())),
      store_(block, StoreOptions(options)) {
  seconds_ = std::chrono::duration<double>(std::chrono::steady_clock::now() - started_).count();
  say("  " + std::string(store_.cached() ? "tiled level images in " + *options.image_cache_dir
                                         : "level images in memory: " + std::to_string(store_.MemoryMb()) + " MB"));
  if (options.adjustment.silhouette_weight <= 0.0) return;
  // The silhouette term: each image's foreground outline as a signed distance.
  const HullViews views = ReadHullViews(block, options.silhouette_foreground);
  silhouettes_.resize(views.masks.size());
  tbb::parallel_for(size_t{0}, views.masks.size(), [&](size_t k) {
    silhouettes_[k] = {views.cameras[k], views.cam_from_world[k], SignedDistanceToOutline(views.masks[k])};
  });
  for (size_t k = 0; k < silhouettes_.size(); ++k) silhouette_of_[block.images[k].image_id] = &silhouettes_[k];
  say("  silhouettes: " + std::to_string(silhouettes_.size()) + " images, background <= " +
      std::to_string(options.silhouette_foreground.background_max) + ", weight " +
      std::to_string(options.adjustment.silhouette_weight));
}

WindowImages LevelImageSource::ForWindows(int level) const {
  return [this, level](const Eigen::AlignedBox3d& box, ImageStorage* storage) {
    std::vector<LevelImage> images = store_.Seeing(level, box, storage);
    for (LevelImage& image : images) {
      const auto found = silhouette_of_.find(image.image_id);
      if (found != silhouette_of_.end()) image.silhouette = found->second;
    }
    return images;
  };
}

}  // namespace facets
