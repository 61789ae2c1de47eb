#include "engine/pipeline/region_choice.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <vector>

#include "io/image_frame.h"

namespace facets {
namespace {

// Point-in-frame tests spent on counting the images over the tie points (each a
// projection through the lens model, some 20 ns): beyond it the count is made on every
// k-th point, which leaves the percentiles of a block of millions of points about where
// they are.
constexpr double kMaxFrameTests = 2e7;
// Fewer well-covered points than this: the region comes from all of them.
constexpr size_t kMinRegionPoints = 10;

double Percentile(std::vector<double> v, double q) {
  std::sort(v.begin(), v.end());
  return v[static_cast<size_t>(std::clamp(q, 0.0, 1.0) * (v.size() - 1))];
}

// The bulk of the points: 2nd to 98th percentile per axis, robust to a few blunders.
RegionOfInterest BulkOf(const std::vector<Eigen::Vector3d>& points) {
  std::vector<double> x, y, z;
  for (const Eigen::Vector3d& p : points) {
    x.push_back(p.x());
    y.push_back(p.y());
    z.push_back(p.z());
  }
  RegionOfInterest roi;
  roi.min = Eigen::Vector3d(Percentile(x, 0.02), Percentile(y, 0.02), Percentile(z, 0.02));
  roi.max = Eigen::Vector3d(Percentile(x, 0.98), Percentile(y, 0.98), Percentile(z, 0.98));
  return roi;
}

// Tie points see everything the images see: an oblique image looks over hundreds of metres
// beyond the block, and the outer images of any block cover a wide margin that one or
// two frames reach. The block was flown for where many frames overlap. A point is well
// covered when it lies inside the frames (in front, no occlusion) of at least half as many
// images as the best-covered points (the 98th percentile of the count), and of at least
// 2 (a count of images). On block_oblique's SIFT points (3 x 3 nadir images with 70 %
// overlap, 12 obliques) every point of its 80 x 70 m block lies inside 14 to 21 frames,
// 98 % of those more than 60 m from its centre inside 10 or fewer; around an object or
// before a facade nearly every image sees nearly every point and the rule keeps them.
std::vector<Eigen::Vector3d> WellCoveredPoints(const ImageBlock& block, std::string* how) {
  const size_t tests = block.points.size() * std::max<size_t>(1, block.images.size());
  const size_t stride = static_cast<size_t>(std::ceil(static_cast<double>(tests) / kMaxFrameTests));
  std::vector<const TiePoint*> sample;
  for (size_t i = 0; i < block.points.size(); i += std::max<size_t>(1, stride)) sample.push_back(&block.points[i]);
  std::vector<int> frames(sample.size(), 0);
  for (const BlockImage& image : block.images) {
    const ImageFrame frame(block.CameraOf(image));
    for (size_t i = 0; i < sample.size(); ++i) frames[i] += frame.Contains(image, sample[i]->xyz) ? 1 : 0;
  }
  std::vector<double> counts(frames.begin(), frames.end());
  const int full = static_cast<int>(Percentile(counts, 0.98));
  const int needed = std::max(2, (full + 1) / 2);
  std::vector<Eigen::Vector3d> covered;
  for (size_t i = 0; i < sample.size(); ++i) {
    if (frames[i] >= needed) covered.push_back(sample[i]->xyz);
  }
  if (how) {
    *how = "tie points: " + std::to_string(covered.size()) + " of " + std::to_string(sample.size()) +
           " inside at least " + std::to_string(needed) + " image frames (half of the best-covered " +
           std::to_string(full) + ")";
  }
  return covered;
}

}  // namespace

RegionOfInterest ChooseRegion(const ImageBlock& block, const std::optional<RegionOfInterest>& given,
                              std::string* how) {
  if (given) {
    if (how) *how = "given";
    return *given;
  }
  if (block.roi) {
    if (how) *how = "the block's";
    return *block.roi;
  }
  if (block.points.size() >= kMinRegionPoints) {
    const std::vector<Eigen::Vector3d> covered = WellCoveredPoints(block, how);
    if (covered.size() >= kMinRegionPoints) return BulkOf(covered);
    std::vector<Eigen::Vector3d> all;
    for (const TiePoint& p : block.points) all.push_back(p.xyz);
    if (how) *how = "all " + std::to_string(all.size()) + " tie points (too few inside enough image frames)";
    return BulkOf(all);
  }
  throw std::runtime_error(
      "no region of interest: the block has none, none was given, and there are fewer "
      "than 10 tie points to derive one from");
}

std::string DescribeRegion(const RegionOfInterest& roi) {
  char text[160];
  std::snprintf(text, sizeof(text), "x %.6g..%.6g, y %.6g..%.6g, z %.6g..%.6g m", roi.min.x(), roi.max.x(),
                roi.min.y(), roi.max.y(), roi.min.z(), roi.max.z());
  return text;
}

}  // namespace facets
