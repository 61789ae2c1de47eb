#include "engine/images/pyramid.h"

#include <algorithm>
#include <stdexcept>

namespace facets {

PyramidFilter PyramidFilterFromName(const std::string& name) {
  if (name == "binomial3") return PyramidFilter::kBinomial3;
  if (name == "binomial5") return PyramidFilter::kBinomial5;
  if (name == "meer13") return PyramidFilter::kMeer13;
  throw std::invalid_argument("unknown pyramid filter '" + name +
                              "' (known: binomial3, binomial5, meer13)");
}

std::vector<double> PyramidKernel(PyramidFilter filter) {
  switch (filter) {
    case PyramidFilter::kBinomial3:
      return {0.25, 0.5, 0.25};
    case PyramidFilter::kBinomial5:
      return {1 / 16.0, 4 / 16.0, 6 / 16.0, 4 / 16.0, 1 / 16.0};
    case PyramidFilter::kMeer13: {
      // Seed 001, Fig. 3.1: a = 1e-3 (0, 51, 0, -87, 0, 298, 475, 298, 0, -87, 0, 51, 0);
      // the taps sum to 0.999, normalised here so flat areas keep their grey value.
      std::vector<double> a = {0, 51, 0, -87, 0, 298, 475, 298, 0, -87, 0, 51, 0};
      double sum = 0;
      for (double v : a) sum += v;
      for (double& v : a) v /= sum;
      return a;
    }
  }
  throw std::logic_error("PyramidKernel: unknown filter");
}

ImagePlanes ReduceImage(const ImagePlanes& image, PyramidFilter filter) {
  // Odd kernel convolved with the half-pixel pair average: an even-length kernel
  // whose centre lies between two input pixels.
  const std::vector<double> odd = PyramidKernel(filter);
  std::vector<double> kernel(odd.size() + 1, 0.0);
  for (size_t i = 0; i < odd.size(); ++i) {
    kernel[i] += 0.5 * odd[i];
    kernel[i + 1] += 0.5 * odd[i];
  }
  const int half = static_cast<int>(odd.size() / 2);  // taps left of the pair's left pixel
  const int w = image.width, h = image.height;
  const int out_w = (w + 1) / 2, out_h = (h + 1) / 2;
  ImagePlanes out;
  out.width = out_w;
  out.height = out_h;
  out.channels = image.channels;
  out.bits = image.bits;
  out.data.assign(static_cast<size_t>(out_w) * out_h * image.channels, 0.0f);
  std::vector<float> rows(static_cast<size_t>(out_w) * h);  // horizontally reduced
  for (int c = 0; c < image.channels; ++c) {
    for (int y = 0; y < h; ++y) {
      for (int i = 0; i < out_w; ++i) {
        double sum = 0.0;
        for (size_t k = 0; k < kernel.size(); ++k) {
          const int x = std::clamp(2 * i - half + static_cast<int>(k), 0, w - 1);
          sum += kernel[k] * image.at(c, x, y);
        }
        rows[static_cast<size_t>(y) * out_w + i] = static_cast<float>(sum);
      }
    }
    for (int j = 0; j < out_h; ++j) {
      for (int i = 0; i < out_w; ++i) {
        double sum = 0.0;
        for (size_t k = 0; k < kernel.size(); ++k) {
          const int y = std::clamp(2 * j - half + static_cast<int>(k), 0, h - 1);
          sum += kernel[k] * rows[static_cast<size_t>(y) * out_w + i];
        }
        out.at(c, i, j) = static_cast<float>(sum);
      }
    }
  }
  return out;
}

std::vector<ImagePlanes> BuildPyramid(const ImagePlanes& image, int num_levels,
                                      PyramidFilter filter) {
  if (num_levels < 1) throw std::invalid_argument("BuildPyramid: num_levels must be >= 1");
  std::vector<ImagePlanes> levels;
  levels.reserve(num_levels);
  levels.push_back(image);
  for (int l = 1; l < num_levels; ++l) levels.push_back(ReduceImage(levels.back(), filter));
  return levels;
}

}  // namespace facets
