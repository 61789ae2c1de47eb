#include "io/image_cache.h"

#include <OpenImageIO/imagecache.h>
#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cstdio>
#include <vector>
#include <stdexcept>

#include "io/atomic_file.h"

namespace facets {

void WriteTiledFloatImage(const std::string& path, const ImagePlanes& image) {
  auto out = OIIO::ImageOutput::create("tiff");
  if (!out) throw std::runtime_error(path + ": no TIFF writer: " + OIIO::geterror());
  OIIO::ImageSpec spec(image.width, image.height, image.channels, OIIO::TypeDesc::FLOAT);
  spec.tile_width = 64;
  spec.tile_height = 64;
  spec.attribute("compression", "none");  // read back many times, written once
  const std::string tmp = CreateTemporaryBeside(path);
  if (!out->open(tmp, spec)) {
    RemoveTemporary(tmp);
    throw std::runtime_error(path + ": " + out->geterror());
  }
  // Plane-major memory to the file's interleaved channels (a level image is small
  // against the original, one interleaved copy is fine).
  const size_t plane = static_cast<size_t>(image.width) * image.height;
  std::vector<float> interleaved(plane * image.channels);
  for (int c = 0; c < image.channels; ++c) {
    for (size_t i = 0; i < plane; ++i) interleaved[i * image.channels + c] = image.data[c * plane + i];
  }
  if (!out->write_image(OIIO::TypeDesc::FLOAT, interleaved.data()) || !out->close()) {
    const std::string error = out->geterror();
    RemoveTemporary(tmp);
    throw std::runtime_error(path + ": cannot write: " + error);
  }
  CommitTemporary(tmp, path);
}

struct TiledImageReader::Cache {
  OIIO::ImageCache* get = nullptr;
  OIIO::ImageCache* operator->() const { return get; }
};

TiledImageReader::TiledImageReader(double max_memory_mb) : cache_(std::make_unique<Cache>()) {
  cache_->get = OIIO::ImageCache::create(/*shared=*/false);
  (*cache_)->attribute("max_memory_MB", static_cast<float>(max_memory_mb));
}

TiledImageReader::~TiledImageReader() { OIIO::ImageCache::destroy(cache_->get); }

ImagePlanes TiledImageReader::Read(const std::string& path, int x0, int y0, int x1, int y1) const {
  const OIIO::ustring name(path);
  const OIIO::ImageSpec* spec = (*cache_)->imagespec(name);
  if (spec == nullptr) throw std::runtime_error(path + ": cannot open: " + (*cache_)->geterror());
  ImagePlanes out;
  out.channels = spec->nchannels;
  out.bits = 32;
  out.x0 = std::clamp(x0, 0, spec->width);
  out.y0 = std::clamp(y0, 0, spec->height);
  out.width = std::clamp(x1, 0, spec->width) - out.x0;
  out.height = std::clamp(y1, 0, spec->height) - out.y0;
  if (out.width <= 0 || out.height <= 0) {
    out.width = out.height = 0;
    return out;
  }
  out.data.resize(static_cast<size_t>(out.width) * out.height * out.channels);
  for (int c = 0; c < out.channels; ++c) {
    float* plane = out.data.data() + static_cast<size_t>(c) * out.width * out.height;
    if (!(*cache_)->get_pixels(name, 0, 0, out.x0, out.x0 + out.width, out.y0, out.y0 + out.height,
                            0, 1, c, c + 1, OIIO::TypeDesc::FLOAT, plane)) {
      throw std::runtime_error(path + ": cannot read pixels: " + (*cache_)->geterror());
    }
  }
  return out;
}

double TiledImageReader::MemoryMb() const {
  int64_t bytes = 0;
  (*cache_)->getattribute("stat:cache_memory_used", OIIO::TypeDesc::INT64, &bytes);
  return static_cast<double>(bytes) / (1024.0 * 1024.0);
}

}  // namespace facets
