// Images as float planes, read and written via OpenImageIO. The raw pixel layout of
// the file is used: EXIF orientation is NOT applied (the data sets are normalised).
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "io/camera.h"
#include "io/image_block.h"

namespace facets {

// An image as float planes in the file's own grey scale (0..255 for 8 bit, 0..65535 for
// 16 bit, as stored for float files). Plane-major: data[(c * height + y) * width + x].
struct ImagePlanes {
  int width = 0, height = 0, channels = 0;
  int bits = 8;   // bit depth of the source file (8, 16, 32 for float)
  // Pixel (x0, y0) of the whole image is the first stored pixel: a region read from a
  // larger image (io/image_cache.h). at() takes whole-image pixel indices.
  int x0 = 0, y0 = 0;
  std::vector<float> data;
  bool Holds(int x, int y) const {
    return x >= x0 && y >= y0 && x < x0 + width && y < y0 + height;
  }
  float& at(int c, int x, int y);
  float at(int c, int x, int y) const;
  // Mean over channels into one grey plane.
  ImagePlanes Grey() const;
  // The first stored pixel of row y (whole-image index) of channel c.
  const float* Row(int c, int y) const {
    return data.data() + (static_cast<size_t>(c) * height + (y - y0)) * width;
  }
  float* Row(int c, int y) { return data.data() + (static_cast<size_t>(c) * height + (y - y0)) * width; }
  // Row y (whole-image index) channel-major: row[c * width + x], width * channels floats.
  void GetRow(int y, float* row) const;
  void SetRow(int y, const float* row);
};

// Inline: called once per pixel ray in the inner loops.
inline float& ImagePlanes::at(int c, int x, int y) {
  return data[(static_cast<size_t>(c) * height + (y - y0)) * width + (x - x0)];
}
inline float ImagePlanes::at(int c, int x, int y) const {
  return data[(static_cast<size_t>(c) * height + (y - y0)) * width + (x - x0)];
}

// Size, channels and bit depth from the file's header (no pixels decoded).
struct ImageHeader {
  int width = 0, height = 0, channels = 0;
  int bits = 8;  // 8, 16, or 32 for float
};
ImageHeader ReadImageHeader(const std::string& path);

ImagePlanes ReadImage(const std::string& path);          // via OpenImageIO
// The image top to bottom in strips of `rows` full-width rows (ImagePlanes::y0 = the
// strip's first row; the last strip may be shorter), each strip starting `overlap` rows
// before the end of the previous one, so that any `overlap + 1` consecutive rows lie in
// one strip. Memory: one strip and its rows in the file's type, not the whole image.
// Errors name the file.
void ForEachImageStrip(const std::string& path, int rows, int overlap,
                       const std::function<void(const ImagePlanes&)>& strip);
// Reads and checks width/height against the camera; error names file, both sizes.
ImagePlanes ReadImageFor(const std::string& path, const Camera& camera);
// The header of the image at `path`, checked as ReadImageFor checks it (no pixel decoded).
ImageHeader CheckImageHeader(const std::string& path, const Camera& camera);
// CheckImageHeader for every image of the block, in block order: throws
// std::runtime_error naming the first file that is missing, not an image, or not of its
// camera's size.
void CheckImageHeaders(const ImageBlock& block);
// Writes via OpenImageIO (format from extension: .png .tif .jpg ...); bits 8 or 16
// (values are rounded and clamped) or 32 (float TIFF). Temp name + rename.
void WriteImage(const std::string& path, const ImagePlanes& image, int bits = 8);

}  // namespace facets
