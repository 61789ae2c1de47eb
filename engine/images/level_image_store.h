// The images of every pyramid level, for the windows (DESIGN.md section 2): either all
// in memory, or written once as tiled float TIFFs into a cache folder and read per
// window region through OpenImageIO's ImageCache, so that memory stays bounded by the
// windows being adjusted instead of growing with the number and size of the images.
// Both give the same pixels: the pyramid is built over the whole image, read in strips of
// kStripRows rows, each level's rows stored as they complete (engine/images/pyramid.h's
// StreamingPyramid), so reading holds a strip and the filters' rows per image, never the
// full-resolution image (unless level 0 is kept in memory).
#pragma once

#include <Eigen/Geometry>
#include <memory>
#include <string>
#include <vector>

#include "engine/images/pyramid.h"
#include "engine/images/level_image.h"
#include "io/camera.h"
#include "io/image_block.h"
#include "io/image_cache.h"
#include "io/image_io.h"

namespace facets {

// Pixel regions a window read (cache mode); the LevelImages point into it.
using ImageStorage = std::vector<std::unique_ptr<ImagePlanes>>;

// Rows of an image decoded at a time while its pyramid is built.
constexpr int kStripRows = 64;

struct LevelImageStoreOptions {
  int levels = 1;
  // Levels below this one are built (the pyramid starts at the image) but not kept:
  // a run that stops at a coarser finest level (ReconstructionOptions::finest_level)
  // does not hold the full-resolution images. Asking for them throws std::logic_error.
  int first_level = 0;
  PyramidFilter filter = PyramidFilter::kBinomial5;
  bool colour = false;          // keep the channels, else their mean
  std::string cache_dir;        // empty: every level in memory; else tiled TIFFs there
  double cache_memory_mb = 256.0;
};

class LevelImageStore {
 public:
  // Reads every image (TBB-parallel; errors name the file), builds its pyramid and keeps
  // it or writes it to the cache folder (created; its files are removed again by the
  // destructor). Cameras are scaled per level like the images.
  LevelImageStore(const ImageBlock& block, const LevelImageStoreOptions& options);
  ~LevelImageStore();
  LevelImageStore(const LevelImageStore&) = delete;
  LevelImageStore& operator=(const LevelImageStore&) = delete;

  int channels() const { return channels_; }
  bool cached() const { return !options_.cache_dir.empty(); }
  const Camera& camera(size_t image, int level) const { return cameras_[image][level]; }

  // Every image of the level whole (object lifting on the small coarsest level).
  std::vector<LevelImage> Whole(int level, ImageStorage* storage) const;
  // The images whose view overlaps `box`, with pixels covering its projection (grown by
  // margin_px); in memory mode the whole images.
  std::vector<LevelImage> Seeing(int level, const Eigen::AlignedBox3d& box,
                                 ImageStorage* storage, int margin_px = 8) const;
  // Bytes held: the in-memory pyramids, or the cache's tiles now.
  double MemoryMb() const;

 private:
  // Reads image k strip by strip into its pyramid, keeping the levels from first_level
  // on (in memory or tiled files); returns its channels. Errors name the file.
  int BuildLevels(size_t image);
  std::string LevelPath(size_t image, int level) const;
  void CheckLevel(int level) const;  // throws std::logic_error for a level not kept
  LevelImage Make(size_t image, int level, const ImagePlanes* pixels) const;

  const ImageBlock& block_;
  LevelImageStoreOptions options_;
  int channels_ = 1;
  std::vector<std::vector<Camera>> cameras_;        // [image][level]
  std::vector<std::vector<ImagePlanes>> pyramids_;  // memory mode: [image][level]
  std::unique_ptr<TiledImageReader> reader_;        // cache mode
  std::vector<std::string> written_;
};

}  // namespace facets
