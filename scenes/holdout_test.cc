#include "scenes/holdout.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

namespace facets {
namespace {

ImagePlanes Plane(int width, int height, float value = 0.0f) {
  ImagePlanes plane;
  plane.width = width;
  plane.height = height;
  plane.channels = 1;
  plane.data.assign(static_cast<size_t>(width) * height, value);
  return plane;
}

// Uniform random grey values in [20, 230).
ImagePlanes Textured(int width, int height, unsigned seed) {
  ImagePlanes plane = Plane(width, height);
  std::mt19937 random(seed);
  std::uniform_real_distribution<float> grey(20.0f, 230.0f);
  for (float& value : plane.data) value = grey(random);
  return plane;
}

TEST(HoldoutScoreTest, ZnccOfIdenticalAndAffineWindowsIsOne) {
  const std::vector<float> a = {3, 9, 1, 7, 4, 4, 8, 2, 6};
  std::vector<float> affine;
  for (float value : a) affine.push_back(0.5f * value + 40.0f);
  EXPECT_NEAR(Zncc(a, a), 1.0, 1e-12);
  EXPECT_NEAR(Zncc(a, affine), 1.0, 1e-12);
  std::vector<float> negated;
  for (float value : a) negated.push_back(100.0f - value);
  EXPECT_NEAR(Zncc(a, negated), -1.0, 1e-12);
  EXPECT_TRUE(std::isnan(Zncc(a, std::vector<float>(9, 5.0f))));
}

TEST(HoldoutScoreTest, WindowsOfAnAffineCopyAllScoreOne) {
  const ImagePlanes real = Textured(20, 15, 3);
  ImagePlanes rendered = real;
  for (float& value : rendered.data) value = 1.7f * value - 12.0f;
  // A 7 x 7 window fits with its centre in 14 x 9 positions; one uncovered pixel at
  // (10, 7) removes the 7 x 7 centres around it that lie inside those positions.
  const std::vector<double> all = WindowZncc(real, rendered, 7, 1.0);
  ASSERT_EQ(all.size(), 14u * 9u);
  for (double score : all) EXPECT_NEAR(score, 1.0, 1e-6);
  rendered.at(0, 10, 7) = std::numeric_limits<float>::quiet_NaN();
  EXPECT_EQ(WindowZncc(real, rendered, 7, 1.0).size(), 14u * 9u - 7u * 7u);
}

TEST(HoldoutScoreTest, LinearFitRemovesGainAndOffset) {
  const ImagePlanes real = Textured(30, 20, 5);
  ImagePlanes rendered = real;
  // real = 1.25 * rendered + 8  <=>  rendered = (real - 8) / 1.25
  for (float& value : rendered.data) value = (value - 8.0f) / 1.25f;
  rendered.data[0] = std::numeric_limits<float>::quiet_NaN();
  const LinearFit fit = FitGainOffset(real, rendered);
  EXPECT_EQ(fit.count, 30 * 20 - 1);
  EXPECT_NEAR(fit.gain, 1.25, 1e-4);
  EXPECT_NEAR(fit.offset, 8.0, 1e-2);
  EXPECT_NEAR(fit.rms, 0.0, 1e-2);
}

TEST(HoldoutScoreTest, ImageScoreCountsCoverageAndObject) {
  const ImagePlanes real = Textured(40, 30, 7);
  ImagePlanes rendered = real;
  for (int y = 0; y < 30; ++y) {
    for (int x = 20; x < 40; ++x) rendered.at(0, x, y) = std::numeric_limits<float>::quiet_NaN();
  }
  PixelMask object(40, 30);
  for (int y = 0; y < 30; ++y) {
    for (int x = 10; x < 30; ++x) object.at(x, y) = 1;
  }
  const HoldoutImageScore score = ScoreHoldoutImage("a.png", real, rendered, HoldoutOptions{}, &object);
  EXPECT_EQ(score.pixels, 1200);
  EXPECT_EQ(score.covered, 600);
  EXPECT_EQ(score.object_pixels, 600);
  EXPECT_EQ(score.object_covered, 300);
  EXPECT_DOUBLE_EQ(score.FrameCoverage(), 0.5);
  EXPECT_DOUBLE_EQ(score.ObjectCoverage(), 0.5);
  EXPECT_EQ(score.windows, 14 * 24);  // centres x in 3..16, y in 3..26
  EXPECT_NEAR(score.zncc_median, 1.0, 1e-6);
  EXPECT_NEAR(score.fit.rms, 0.0, 1e-3);
}

TEST(HoldoutScoreTest, QuantileTakesTheLowerNeighbour) {
  EXPECT_DOUBLE_EQ(Quantile({5, 1, 4, 2, 3}, 0.5), 3.0);
  EXPECT_DOUBLE_EQ(Quantile({5, 1, 4, 2, 3, 6}, 0.5), 3.0);
  EXPECT_DOUBLE_EQ(Quantile({10, 1, 9, 2, 8, 3, 7, 4, 6, 5, 0}, 0.1), 1.0);
  EXPECT_TRUE(std::isnan(Quantile({}, 0.5)));
}


// With an even number of held-out images each summary column is the mean of its two
// middle values, so no column takes one image's value and another column the other's.
TEST(HoldoutScoreTest, SummaryOfTwoImagesIsTheirMean) {
  HoldoutReport report;
  report.images.resize(2);
  report.images[0].zncc_median = 0.946;
  report.images[0].fit.rms = 5.80;
  report.images[0].pixels = 100;
  report.images[0].covered = 90;
  report.images[1].zncc_median = 0.932;
  report.images[1].fit.rms = 7.64;
  report.images[1].pixels = 100;
  report.images[1].covered = 70;
  report.images[1].zncc_p10 = 0.6;
  SummariseHoldout(&report);
  EXPECT_DOUBLE_EQ(report.zncc_median, 0.5 * (0.946 + 0.932));
  EXPECT_DOUBLE_EQ(report.rms, 0.5 * (5.80 + 7.64));
  EXPECT_DOUBLE_EQ(report.frame_coverage, 0.8);
  EXPECT_DOUBLE_EQ(report.zncc_p10, 0.6);  // the one image that has a value
  report.images.push_back(report.images[0]);
  report.images[2].zncc_median = 0.1;
  SummariseHoldout(&report);
  EXPECT_DOUBLE_EQ(report.zncc_median, 0.932);  // odd count: the middle one
}

}  // namespace
}  // namespace facets
