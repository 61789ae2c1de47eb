// Images on disk, read by region (DESIGN.md section 2: memory bounded by the window,
// not the scene). Pyramid levels are written once as tiled float TIFFs; windows then
// read the pixels their surface projects onto through OpenImageIO's ImageCache, which
// keeps at most `max_memory_mb` of tiles in memory and reads each 64 x 64 tile once
// while it stays in use.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "io/image_io.h"

namespace facets {

// Side of the square tiles of the files written here, pixels.
constexpr int kTileSize = 64;

// A tiled float TIFF written row by row: rows are held until a band of tiles is complete,
// so a large level image never has to be whole in memory. Written under a temporary
// name, renamed into place by Close(); a writer destroyed before Close() removes it.
class TiledFloatImageWriter {
 public:
  TiledFloatImageWriter(const std::string& path, int width, int height, int channels);
  ~TiledFloatImageWriter();
  TiledFloatImageWriter(const TiledFloatImageWriter&) = delete;
  TiledFloatImageWriter& operator=(const TiledFloatImageWriter&) = delete;

  // The next row, channel-major: row[c * width + x].
  void AddRow(const float* row);
  // After the last row. Throws std::runtime_error naming the file.
  void Close();

 private:
  struct Output;  // OpenImageIO's ImageOutput, kept out of this header
  std::unique_ptr<Output> out_;
  std::string path_, tmp_;
  int width_ = 0, height_ = 0, channels_ = 0;
  int rows_ = 0;             // rows added
  std::vector<float> band_;  // the rows of the current band of tiles, interleaved
};

// Writes a tiled float TIFF, one channel per plane (temporary name + rename).
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
