#include "io/image_cache.h"

#include <OpenImageIO/imagecache.h>
#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cstdio>
#include <vector>
#include <stdexcept>

#include "io/atomic_file.h"

namespace facets {

struct TiledFloatImageWriter::Output {
  std::unique_ptr<OIIO::ImageOutput> get;
};

TiledFloatImageWriter::TiledFloatImageWriter(const std::string& path, int width, int height, int channels)
    : out_(std::make_unique<Output>()), path_(path), tmp_(CreateTemporaryBeside(path)), width_(width), height_(height),
      channels_(channels) {
  out_->get = OIIO::ImageOutput::create("tiff");
  if (!out_->get) {
    RemoveTemporary(tmp_);
    throw std::runtime_error(path + ": no TIFF writer: " + OIIO::geterror());
  }
  OIIO::ImageSpec spec(width, height, channels, OIIO::TypeDesc::FLOAT);
  spec.tile_width = kTileSize;
  spec.tile_height = kTileSize;
  spec.attribute("compression", "none");  // read back many times, written once
  if (!out_->get->open(tmp_, spec)) {
    RemoveTemporary(tmp_);
    throw std::runtime_error(path + ": " + out_->get->geterror());
  }
  band_.resize(static_cast<size_t>(kTileSize) * width * channels);
}

TiledFloatImageWriter::~TiledFloatImageWriter() {
  if (!out_->get) return;  // closed
  out_->get->close();
  RemoveTemporary(tmp_);
}

void TiledFloatImageWriter::AddRow(const float* row) {
  if (rows_ >= height_) throw std::logic_error(path_ + ": more rows than the image has");
  float* interleaved = band_.data() + static_cast<size_t>(rows_ % kTileSize) * width_ * channels_;
  for (int c = 0; c < channels_; ++c)
    for (int x = 0; x < width_; ++x) interleaved[x * channels_ + c] = row[c * width_ + x];
  ++rows_;
  if (rows_ % kTileSize != 0 && rows_ != height_) return;
  const int band_y0 = (rows_ - 1) / kTileSize * kTileSize;
  if (!out_->get->write_tiles(0, width_, band_y0, rows_, 0, 1, OIIO::TypeDesc::FLOAT, band_.data())) {
    throw std::runtime_error(path_ + ": cannot write: " + out_->get->geterror());
  }
}

void TiledFloatImageWriter::Close() {
  if (rows_ != height_) throw std::logic_error(path_ + ": closed after " + std::to_string(rows_) + " rows");
  if (!out_->get->close()) throw std::runtime_error(path_ + ": cannot write: " + out_->get->geterror());
  out_->get.reset();
  CommitTemporary(tmp_, path_);
}

void WriteTiledFloatImage(const std::string& path, const ImagePlanes& image) {
  TiledFloatImageWriter writer(path, image.width, image.height, image.channels);
  std::vector<float> row(static_cast<size_t>(image.width) * image.channels);
  for (int y = image.y0; y < image.y0 + image.height; ++y) {
    image.GetRow(y, row.data());
    writer.AddRow(row.data());
  }
  writer.Close();
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
