#include "engine/images/level_image_store.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <filesystem>
#include <memory>
#include <new>
#include <stdexcept>
#include <string>

#include "visibility/image_selection.h"

namespace facets {
namespace {

// Row y of the strip as the mean of its channels (the arithmetic of ImagePlanes::Grey).
void GreyRow(const ImagePlanes& strip, int y, float* grey) {
  std::fill_n(grey, strip.width, 0.0f);
  for (int c = 0; c < strip.channels; ++c) {
    const float* in = strip.Row(c, y);
    for (int x = 0; x < strip.width; ++x) grey[x] += in[x];
  }
  const float scale = 1.0f / static_cast<float>(strip.channels);
  for (int x = 0; x < strip.width; ++x) grey[x] *= scale;
}

}  // namespace

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
    cameras_[k].push_back(block.CameraOf(block.images[k]));
    for (int l = 1; l < options.levels; ++l) cameras_[k].push_back(cameras_[k].back().Scaled(0.5));
    try {
      channels[k] = BuildLevels(k);
    } catch (const std::bad_alloc&) {
      const Camera& camera = cameras_[k][0];
      throw std::runtime_error(block.images[k].path + ": out of memory building the image's pyramid (" +
                               std::to_string(camera.width) + " x " + std::to_string(camera.height) +
                               " pixels); lower --image-memory so that the level images go to tiled files");
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

int LevelImageStore::BuildLevels(size_t k) {
  const std::string& path = block_.images[k].path;
  const Camera& camera = cameras_[k][0];
  const ImageHeader header = ReadImageHeader(path);
  if (header.width != camera.width || header.height != camera.height) {
    throw std::runtime_error(path + ": image is " + std::to_string(header.width) + "x" + std::to_string(header.height) +
                             " pixels but camera " + std::to_string(camera.camera_id) + " expects " +
                             std::to_string(camera.width) + "x" + std::to_string(camera.height));
  }
  const int channels = options_.colour ? header.channels : 1;
  // Each level's rows go to its tiled file or its plane in memory as they complete.
  std::vector<std::unique_ptr<TiledFloatImageWriter>> files(options_.levels);
  std::vector<ImagePlanes> levels(options_.levels);
  for (int l = options_.first_level; l < options_.levels; ++l) {
    const Camera& level = cameras_[k][l];
    if (cached()) {
      files[l] = std::make_unique<TiledFloatImageWriter>(LevelPath(k, l), level.width, level.height, channels);
      continue;
    }
    levels[l].width = level.width;
    levels[l].height = level.height;
    levels[l].channels = channels;
    levels[l].bits = header.bits;
    levels[l].data.resize(static_cast<size_t>(level.width) * level.height * channels);
  }
  StreamingPyramid pyramid(header.width, header.height, channels, options_.levels, options_.filter,
                           [&](int l, int y, const float* row) {
                             if (l < options_.first_level) return;
                             if (files[l]) files[l]->AddRow(row);
                             else levels[l].SetRow(y, row);
                           });
  std::vector<float> row(static_cast<size_t>(header.width) * channels);
  ForEachImageStrip(path, kStripRows, 0, [&](const ImagePlanes& strip) {
    for (int y = strip.y0; y < strip.y0 + strip.height; ++y) {
      if (channels == strip.channels) {
        strip.GetRow(y, row.data());
      } else {
        GreyRow(strip, y, row.data());
      }
      pyramid.AddRow(row.data());
    }
  });
  for (auto& file : files)
    if (file) file->Close();
  if (!cached()) pyramids_[k] = std::move(levels);
  return channels;
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
