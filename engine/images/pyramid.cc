#include "engine/images/pyramid.h"

#include <algorithm>
#include <stdexcept>
#include <utility>

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

StreamingPyramid::StreamingPyramid(int width, int height, int channels, int num_levels, PyramidFilter filter,
                                   RowSink sink)
    : channels_(channels), sink_(std::move(sink)) {
  if (num_levels < 1) throw std::invalid_argument("StreamingPyramid: num_levels must be >= 1");
  if (width < 1 || height < 1 || channels < 1) throw std::invalid_argument("StreamingPyramid: empty image");
  // Odd kernel convolved with the half-pixel pair average: an even-length kernel whose
  // centre lies between two input pixels.
  const std::vector<double> odd = PyramidKernel(filter);
  kernel_.assign(odd.size() + 1, 0.0);
  for (size_t i = 0; i < odd.size(); ++i) {
    kernel_[i] += 0.5 * odd[i];
    kernel_[i + 1] += 0.5 * odd[i];
  }
  half_ = static_cast<int>(odd.size() / 2);  // taps left of the pair's left pixel
  for (int l = 0; l < num_levels; ++l) {
    Level level;
    level.width = width;
    level.height = height;
    if (l + 1 < num_levels) level.ring.resize(kernel_.size() * static_cast<size_t>((width + 1) / 2) * channels);
    levels_.push_back(std::move(level));
    width = (width + 1) / 2;
    height = (height + 1) / 2;
  }
}

size_t StreamingPyramid::HeldFloats() const {
  size_t floats = 0;
  for (const Level& level : levels_) floats += level.ring.size() + static_cast<size_t>(level.width) * channels_;
  return floats;
}

void StreamingPyramid::AddRow(const float* row) { Add(0, row); }

void StreamingPyramid::Add(int l, const float* row) {
  Level& level = levels_[l];
  const int y = level.rows_in++;
  sink_(l, y, row);
  if (level.ring.empty()) return;
  // Horizontal reduction of this row into the ring of the kernel's rows.
  const int w = level.width, out_w = (w + 1) / 2, taps = static_cast<int>(kernel_.size());
  float* reduced = level.ring.data() + static_cast<size_t>(y % taps) * out_w * channels_;
  for (int c = 0; c < channels_; ++c) {
    for (int i = 0; i < out_w; ++i) {
      double sum = 0.0;
      for (int k = 0; k < taps; ++k) sum += kernel_[k] * row[c * w + std::clamp(2 * i - half_ + k, 0, w - 1)];
      reduced[c * out_w + i] = static_cast<float>(sum);
    }
  }
  // Rows of the next level whose taps have all arrived (borders replicated).
  const int out_h = (level.height + 1) / 2;
  std::vector<float> out(static_cast<size_t>(out_w) * channels_);
  while (level.next_out < out_h && std::min(2 * level.next_out - half_ + taps - 1, level.height - 1) <= y) {
    const int j = level.next_out++;
    for (int c = 0; c < channels_; ++c) {
      for (int i = 0; i < out_w; ++i) {
        double sum = 0.0;
        for (int k = 0; k < taps; ++k) {
          const int source = std::clamp(2 * j - half_ + k, 0, level.height - 1);
          sum += kernel_[k] * level.ring[(static_cast<size_t>(source % taps) * channels_ + c) * out_w + i];
        }
        out[c * out_w + i] = static_cast<float>(sum);
      }
    }
    Add(l + 1, out.data());
  }
}

ImagePlanes ReduceImage(const ImagePlanes& image, PyramidFilter filter) {
  return BuildPyramid(image, 2, filter)[1];
}

std::vector<ImagePlanes> BuildPyramid(const ImagePlanes& image, int num_levels,
                                      PyramidFilter filter) {
  if (num_levels < 1) throw std::invalid_argument("BuildPyramid: num_levels must be >= 1");
  std::vector<ImagePlanes> levels(num_levels);
  int w = image.width, h = image.height;
  for (ImagePlanes& level : levels) {
    level.width = w;
    level.height = h;
    level.channels = image.channels;
    level.bits = image.bits;
    level.data.resize(static_cast<size_t>(w) * h * image.channels);
    w = (w + 1) / 2;
    h = (h + 1) / 2;
  }
  StreamingPyramid pyramid(image.width, image.height, image.channels, num_levels, filter,
                           [&levels](int l, int y, const float* row) { levels[l].SetRow(y, row); });
  std::vector<float> row(static_cast<size_t>(image.width) * image.channels);
  for (int y = 0; y < image.height; ++y) {
    image.GetRow(y, row.data());
    pyramid.AddRow(row.data());
  }
  return levels;
}

}  // namespace facets
