// Image pyramid (DESIGN.md section 5, seed 001): low-pass filter, then halve the
// resolution, per level. Level 0 is the original image.
//
// Pixel-centre convention (io/camera.h): the centre of the top-left pixel is at
// (0.5, 0.5). A level-(l+1) pixel i has its centre at level-l coordinate 2i + 1, i.e.
// midway between level-l pixels 2i and 2i + 1. The reduction therefore filters with
// the chosen odd kernel and then averages each pixel pair (2-tap box at half-pixel
// offset), so that Camera::Scaled(0.5) describes the reduced image exactly.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "io/image_io.h"

namespace facets {

enum class PyramidFilter {
  kBinomial3,  // 1/4 (1 2 1)
  kBinomial5,  // 1/16 (1 4 6 4 1)
  kMeer13,     // 13-tap half-band mask of seed 001 (Meer et al. 1987), really 7 taps
};

// "binomial3", "binomial5", "meer13"; throws std::invalid_argument otherwise.
PyramidFilter PyramidFilterFromName(const std::string& name);
// The separable 1D kernel (odd length, sums to 1).
std::vector<double> PyramidKernel(PyramidFilter filter);

// The pyramid of an image given row by row, top to bottom (level 0 = the rows given),
// holding per level only the rows its filter spans: every row of every level goes to
// `sink(level, y, row)` as soon as it is complete, rows of a level in order. A row is
// channel-major: row[c * level_width + x]. Gives BuildPyramid's values to the bit.
class StreamingPyramid {
 public:
  using RowSink = std::function<void(int level, int y, const float* row)>;
  StreamingPyramid(int width, int height, int channels, int num_levels, PyramidFilter filter, RowSink sink);
  void AddRow(const float* row);
  // Floats held between rows (the filters' rows), for memory estimates.
  size_t HeldFloats() const;

 private:
  struct Level {
    int width = 0, height = 0;
    int rows_in = 0;   // rows of this level given so far
    int next_out = 0;  // next row of the level below to complete
    std::vector<float> ring;  // the last kernel-size rows, reduced horizontally
  };
  void Add(int level, const float* row);

  int channels_ = 1;
  int half_ = 0;
  std::vector<double> kernel_;
  std::vector<Level> levels_;
  RowSink sink_;
};

// One reduction step: filter separably (borders replicated), then halve. The result
// has ceil(width/2) x ceil(height/2) pixels and the same channels and bit depth.
ImagePlanes ReduceImage(const ImagePlanes& image, PyramidFilter filter);

// Levels 0..num_levels-1 (level 0 = the image itself).
std::vector<ImagePlanes> BuildPyramid(const ImagePlanes& image, int num_levels,
                                      PyramidFilter filter);

}  // namespace facets
