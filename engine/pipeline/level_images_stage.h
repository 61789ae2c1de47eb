// Stage "images": every image's pyramid (cameras scaled level by level like the
// images), in memory or as tiled files read per window, and each image's foreground
// outline when the silhouette term is on. The windows, the searches and the start read
// their level images here.
#pragma once

#include <chrono>
#include <functional>
#include <string>
#include <unordered_map>
#include <vector>

#include "engine/images/level_image_store.h"
#include "engine/pipeline/level_windows.h"
#include "io/image_block.h"
#include "visibility/silhouette.h"

namespace facets {

struct ReconstructionOptions;

class LevelImageSource {
 public:
  LevelImageSource(const ImageBlock& block, const ReconstructionOptions& options,
                   const std::function<void(const std::string&)>& say);
  LevelImageSource(const LevelImageSource&) = delete;
  LevelImageSource& operator=(const LevelImageSource&) = delete;

  // Whole level images, their pixels in *storage.
  std::vector<LevelImage> Whole(int level, ImageStorage* storage) const { return store_.Whole(level, storage); }
  // Whole level images whose pixels live as long as the run (object lifting, the
  // closed start's scale search).
  std::vector<LevelImage> WholeForRun(int level) const { return store_.Whole(level, &run_storage_); }
  // The images a window on this level gets, with their silhouettes.
  WindowImages ForWindows(int level) const;

  int channels() const { return store_.channels(); }
  bool cached() const { return store_.cached(); }
  double seconds() const { return seconds_; }  // reading the images and building the pyramids

 private:
  std::chrono::steady_clock::time_point started_;  // before the store reads the images
  LevelImageStore store_;
  std::vector<SilhouetteView> silhouettes_;
  std::unordered_map<int, const SilhouetteView*> silhouette_of_;
  mutable ImageStorage run_storage_;
  double seconds_ = 0.0;
};

}  // namespace facets
