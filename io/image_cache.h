// Images on disk, read by region (DESIGN.md section 2: memory bounded by the window,
// not the scene). Pyramid levels are written once as tiled float TIFFs; windows then
// read the pixels their surface projects onto through OpenImageIO's ImageCache, which
// keeps at most `max_memory_mb` of tiles in memory and reads each 64 x 64 tile once
// while it stays in use.
#pragma once

#include <memory>
#include <string>

#include "io/image_io.h"

namespace facets {

// Writes a tiled (64 x 64) float TIFF, one channel per plane (temporary name + rename).
void WriteTiledFloatImage(const std::string& path, const ImagePlanes& image);

class TiledImageReader {
 public:
  explicit TiledImageReader(double max_memory_mb = 256.0);
  ~TiledImageReader();
  TiledImageReader(const TiledImageReader&) = delete;
  TiledImageReader& operator=(const TiledImageReader&) = delete;

  // Pixels [x0, x1) x [y0, y1) (clipped to the image) of a file written by
  // WriteTiledFloatImage, as planes with origin (x0, y0). Thread-safe. Throws
  // std::runtime_error naming the file.
  ImagePlanes Read(const std::string& path, int x0, int y0, int x1, int y1) const;
  // Bytes of tiles the cache holds now (for reports).
  double MemoryMb() const;

 private:
  struct Cache;  // OpenImageIO's ImageCache, kept out of this header
  std::unique_ptr<Cache> cache_;
};

}  // namespace facets
