#include "engine/images/level_image_store.h"

#include <tbb/parallel_for.h>

#include <filesystem>
#include <mutex>
#include <stdexcept>
#include <string>

#include "visibility/image_selection.h"

namespace facets {

LevelImageStore::LevelImageStore(const ImageBlock& block, const LevelImageStoreOptions& options)
    : block_(block), options_(options) {
  if (options.levels < 1) throw std::invalid_argument("LevelImageStore: levels must be >= 1");
  if (options.first_level < 0 || options.first_level >= options.levels) {
    throw std::invalid_argument("LevelImageStore: first_level must lie in 0..levels-1");
  }
  const size_t n = block.images.size();
  cameras_.resize(n);
  if (cached()) {
    std::filesystem::create_directories(options.cache_dir);
    reader_ = std::make_unique<TiledImageReader>(options.cache_memory_mb);
  } else {
    pyramids_.resize(n);
  }
  std::vector<int> channels(n, 1);
  tbb::parallel_for(size_t{0}, n, [&](size_t k) {
    ImagePlanes planes = ReadImageFor(block.images[k].path, block.CameraOf(block.images[k]));
    if (!options.colour) planes = planes.Grey();
    channels[k] = planes.channels;
    std::vector<ImagePlanes> pyramid = BuildPyramid(planes, options.levels, options.filter);
    cameras_[k].push_back(block.CameraOf(block.images[k]));
    for (int l = 1; l < options.levels; ++l) cameras_[k].push_back(cameras_[k].back().Scaled(0.5));
    if (cached()) {
      for (int l = options.first_level; l < options.levels; ++l) WriteTiledFloatImage(LevelPath(k, l), pyramid[l]);
    } else {
      for (int l = 0; l < options.first_level; ++l) pyramid[l] = ImagePlanes{};  // not used: freed
      pyramids_[k] = std::move(pyramid);
    }
  });
  for (size_t k = 0; k < n; ++k) {
    if (channels[k] != channels[0]) {
      throw std::runtime_error(block.images[k].path + ": " + std::to_string(channels[k]) +
                               " channels, the first image has " + std::to_string(channels[0]) +
                               " (use grey images or the same channels everywhere)");
    }
  }
  channels_ = n > 0 ? channels[0] : 1;
  if (cached()) {
    for (size_t k = 0; k < n; ++k)
      for (int l = options.first_level; l < options.levels; ++l) written_.push_back(LevelPath(k, l));
  }
}

LevelImageStore::~LevelImageStore() {
  reader_.reset();  // closes the files before they go
  std::error_code ignored;
  for (const auto& path : written_) std::filesystem::remove(path, ignored);
  if (cached()) std::filesystem::remove(options_.cache_dir, ignored);  // only when empty
}

std::string LevelImageStore::LevelPath(size_t image, int level) const {
  return (std::filesystem::path(options_.cache_dir) /
          ("image" + std::to_string(image) + "_level" + std::to_string(level) + ".tif"))
      .string();
}

LevelImage LevelImageStore::Make(size_t image, int level, const ImagePlanes* pixels) const {
  return {block_.images[image].image_id, &cameras_[image][level],
          block_.images[image].cam_from_world, pixels};
}

void LevelImageStore::CheckLevel(int level) const {
  if (level < options_.first_level || level >= options_.levels) {
    throw std::logic_error("LevelImageStore: level " + std::to_string(level) + " is not kept (levels " +
                           std::to_string(options_.first_level) + ".." + std::to_string(options_.levels - 1) + ")");
  }
}

std::vector<LevelImage> LevelImageStore::Whole(int level, ImageStorage* storage) const {
  CheckLevel(level);
  std::vector<LevelImage> images;
  for (size_t k = 0; k < block_.images.size(); ++k) {
    if (!cached()) {
      images.push_back(Make(k, level, &pyramids_[k][level]));
      continue;
    }
    const Camera& camera = cameras_[k][level];
    storage->push_back(std::make_unique<ImagePlanes>(
        reader_->Read(LevelPath(k, level), 0, 0, camera.width, camera.height)));
    images.push_back(Make(k, level, storage->back().get()));
  }
  return images;
}

std::vector<LevelImage> LevelImageStore::Seeing(int level, const Eigen::AlignedBox3d& box,
                                                ImageStorage* storage, int margin_px) const {
  CheckLevel(level);
  std::vector<LevelImage> images;
  for (size_t k = 0; k < block_.images.size(); ++k) {
    const Camera& camera = cameras_[k][level];
    const auto rect = ProjectBox(box, camera, block_.images[k].cam_from_world, margin_px);
    if (!rect) continue;
    if (!cached()) {
      images.push_back(Make(k, level, &pyramids_[k][level]));
      continue;
    }
    storage->push_back(std::make_unique<ImagePlanes>(
        reader_->Read(LevelPath(k, level), rect->x0, rect->y0, rect->x1, rect->y1)));
    if (storage->back()->width == 0) {
      storage->pop_back();
      continue;
    }
    images.push_back(Make(k, level, storage->back().get()));
  }
  return images;
}

double LevelImageStore::MemoryMb() const {
  if (cached()) return reader_->MemoryMb();
  double bytes = 0.0;
  for (const auto& pyramid : pyramids_)
    for (const auto& level : pyramid) bytes += level.data.size() * sizeof(float);
  return bytes / (1024.0 * 1024.0);
}

}  // namespace facets
