#include "engine/images/pyramid.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "io/camera.h"

namespace facets {
namespace {

ImagePlanes Ramp(int w, int h, double ax, double ay) {
  ImagePlanes image;
  image.width = w;
  image.height = h;
  image.channels = 1;
  image.data.resize(static_cast<size_t>(w) * h);
  // Value at a pixel = ramp at its centre (x + 0.5, y + 0.5).
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) image.at(0, x, y) = static_cast<float>(ax * (x + 0.5) + ay * (y + 0.5));
  return image;
}

// A linear ramp is reproduced by every symmetric kernel: the reduced pixel i must hold
// the ramp at its centre in level-0 coordinates, (i + 0.5) * 2 — the same mapping that
// Camera::Scaled(0.5) applies to pixel coordinates.
TEST(Pyramid, ReductionMatchesScaledCameraConvention) {
  for (PyramidFilter filter :
       {PyramidFilter::kBinomial3, PyramidFilter::kBinomial5, PyramidFilter::kMeer13}) {
    const ImagePlanes image = Ramp(40, 30, 1.5, -0.75);
    const ImagePlanes half = ReduceImage(image, filter);
    ASSERT_EQ(half.width, 20);
    ASSERT_EQ(half.height, 15);
    for (int j = 4; j < half.height - 4; ++j) {
      for (int i = 4; i < half.width - 4; ++i) {
        EXPECT_NEAR(half.at(0, i, j), 1.5 * 2 * (i + 0.5) - 0.75 * 2 * (j + 0.5), 1e-3);
      }
    }
  }
  // The camera side of the same convention.
  const Camera camera = Camera::Create(CameraModel::kPinhole, 1000, 1000, 20.0, 15.0, 40, 30);
  const Eigen::Vector3d point(0.1, -0.05, 1.0);
  EXPECT_NEAR((camera.Scaled(0.5).ImageFromCam(point) - camera.ImageFromCam(point) / 2).norm(),
              0.0, 1e-12);
}

TEST(Pyramid, KernelsSumToOneAndOddSizesRoundUp) {
  for (PyramidFilter filter :
       {PyramidFilter::kBinomial3, PyramidFilter::kBinomial5, PyramidFilter::kMeer13}) {
    double sum = 0;
    for (double v : PyramidKernel(filter)) sum += v;
    EXPECT_NEAR(sum, 1.0, 1e-15);
  }
  const std::vector<ImagePlanes> levels = BuildPyramid(Ramp(41, 31, 0, 0), 3, PyramidFilter::kBinomial5);
  ASSERT_EQ(levels.size(), 3u);
  EXPECT_EQ(levels[1].width, 21);
  EXPECT_EQ(levels[1].height, 16);
  EXPECT_EQ(levels[2].width, 11);
  EXPECT_EQ(levels[2].height, 8);
  EXPECT_THROW(PyramidFilterFromName("gauss"), std::invalid_argument);
}

// Low-pass: a checkerboard at the Nyquist frequency is removed by the binomial masks.
TEST(Pyramid, NyquistPatternIsRemoved) {
  ImagePlanes image = Ramp(32, 32, 0, 0);
  for (int y = 0; y < 32; ++y)
    for (int x = 0; x < 32; ++x) image.at(0, x, y) = ((x + y) % 2) ? 100.0f : 0.0f;
  const ImagePlanes half = ReduceImage(image, PyramidFilter::kBinomial5);
  for (int j = 2; j < 14; ++j)
    for (int i = 2; i < 14; ++i) EXPECT_NEAR(half.at(0, i, j), 50.0, 1e-4);
}

// Row by row, each level's rows arrive once and in order, and hold the separable filter
// (borders replicated, then the pair average) computed directly on the whole image.
TEST(Pyramid, StreamedRowsMatchTheFilterOnTheWholeImage) {
  for (PyramidFilter filter : {PyramidFilter::kBinomial5, PyramidFilter::kMeer13}) {
    const int w = 37, h = 29;  // odd sizes: the last pair replicates the border
    ImagePlanes image = Ramp(w, h, 0, 0);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) image.at(0, x, y) = static_cast<float>((x * 7 + y * 13) % 23);
    const std::vector<double> odd = PyramidKernel(filter);
    const int half = static_cast<int>(odd.size() / 2);
    // The even kernel of ReduceImage: the odd one convolved with the pair average.
    const int taps = static_cast<int>(odd.size()) + 1;
    auto tap = [&](int k) { return 0.5 * ((k < taps - 1 ? odd[k] : 0.0) + (k > 0 ? odd[k - 1] : 0.0)); };
    std::vector<std::vector<int>> rows(3);
    double worst = 0.0;
    StreamingPyramid pyramid(w, h, 1, 3, filter, [&](int level, int y, const float* row) {
      rows[level].push_back(y);
      if (level != 1) return;
      for (int i = 0; i < (w + 1) / 2; ++i) {
        double expected = 0.0;
        for (int ky = 0; ky < taps; ++ky) {
          const int source_y = std::clamp(2 * y - half + ky, 0, h - 1);
          double across = 0.0;
          for (int kx = 0; kx < taps; ++kx) across += tap(kx) * image.at(0, std::clamp(2 * i - half + kx, 0, w - 1), source_y);
          expected += tap(ky) * static_cast<float>(across);
        }
        worst = std::max(worst, std::abs(expected - row[i]));
      }
    });
    for (int y = 0; y < h; ++y) pyramid.AddRow(&image.at(0, 0, y));
    for (int level = 0; level < 3; ++level) {
      ASSERT_EQ(rows[level].size(), static_cast<size_t>(level == 0 ? 29 : level == 1 ? 15 : 8));
      for (size_t y = 0; y < rows[level].size(); ++y) EXPECT_EQ(rows[level][y], static_cast<int>(y));
    }
    EXPECT_LT(worst, 1e-4);
  }
}

}  // namespace
}  // namespace facets
