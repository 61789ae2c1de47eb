// The region chosen from the tie points on block_oblique's layout (3 x 3 nadir images,
// 12 obliques; 80 x 70 m block): with tie points wherever two frames overlap, as SIFT
// matches triangulated with the known poses are, the region is the block and not the
// land the obliques see beyond it; with the scene's rendered tie points (all on the block)
// it is their bulk, as before.
#include "engine/pipeline/region_choice.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <string>
#include <tuple>
#include <vector>

#include "io/colmap_io.h"
#include "io/image_frame.h"
#include "io/shared_data_for_testing.h"
#include "scenes/camera_layout.h"
#include "scenes/renderer.h"
#include "scenes/scene.h"
#include "scenes/truth_mesh.h"

namespace facets {
namespace {

Scene ObliqueScene() { return LoadScene(std::string(FACETS_SOURCE_DIR) + "/scenes/data/block_oblique.json"); }

double Percentile(std::vector<double> v, double q) {
  std::sort(v.begin(), v.end());
  return v[static_cast<size_t>(q * (v.size() - 1))];
}

// 2nd and 98th percentile of the tie points along one axis (the rule for all points).
std::pair<double, double> BulkAlong(const ImageBlock& block, int axis) {
  std::vector<double> v;
  for (const TiePoint& p : block.points) v.push_back(p.xyz[axis]);
  return {Percentile(v, 0.02), Percentile(v, 0.98)};
}

// Ground points every 4 m over 320 x 320 m at z = 0, each kept when it lies inside at
// least 2 image frames (a match needs two images).
void AddGroundTiePoints(ImageBlock* block) {
  std::vector<ImageFrame> frames;
  for (const BlockImage& image : block->images) frames.emplace_back(block->CameraOf(image));
  long long id = 0;
  for (double y = -160; y <= 160; y += 4) {
    for (double x = -160; x <= 160; x += 4) {
      const Eigen::Vector3d point(x, y, 0.0);
      int seen = 0;
      for (size_t i = 0; i < frames.size(); ++i) seen += frames[i].Contains(block->images[i], point) ? 1 : 0;
      if (seen < 2) continue;
      TiePoint tie;
      tie.point3d_id = ++id;
      tie.xyz = point;
      block->points.push_back(tie);
    }
  }
}

TEST(RegionChoice, ObliqueBlockIgnoresTheLandBeyondIt) {
  const Scene scene = ObliqueScene();
  ImageBlock block = BuildImageBlock(scene);
  block.roi.reset();
  AddGroundTiePoints(&block);
  ASSERT_EQ(block.points.size(), 3729u);
  // All points' bulk: the obliques' view far beyond the block.
  const auto [x_min_all, x_max_all] = BulkAlong(block, 0);
  EXPECT_LT(x_min_all, -90.0);
  EXPECT_GT(x_max_all, 90.0);
  std::string how;
  const RegionOfInterest roi = ChooseRegion(block, std::nullopt, &how);
  EXPECT_EQ(how, "tie points: 825 of 3729 inside at least 11 image frames (half of the best-covered 21)");
  // The block (scene region 80 x 70 m) inside, and at most 1.6 times it along each axis
  // (all points' bulk: 2.9 times along x).
  EXPECT_LE(roi.min.x(), -40.0);
  EXPECT_GE(roi.max.x(), 40.0);
  EXPECT_LE(roi.min.y(), -35.0);
  EXPECT_GE(roi.max.y(), 35.0);
  EXPECT_LE(roi.max.x() - roi.min.x(), 1.6 * 80.0);
  EXPECT_LE(roi.max.y() - roi.min.y(), 1.6 * 70.0);
  std::printf("all points: x %.1f..%.1f; now %s\n", x_min_all, x_max_all, DescribeRegion(roi).c_str());
}

TEST(RegionChoice, RenderedTiePointsKeepTheirBulk) {
  const Scene scene = ObliqueScene();
  const TruthMesh mesh = BuildTruthMesh(scene);
  ImageBlock block = BuildImageBlock(scene);
  const Renderer renderer(scene, mesh);
  SampleTiePoints(scene, mesh, renderer, static_cast<uint32_t>(scene.seed) * 7u + 1u, &block);
  block.roi.reset();
  std::string how;
  const RegionOfInterest roi = ChooseRegion(block, std::nullopt, &how);
  const std::string all = std::to_string(block.points.size());
  EXPECT_EQ(how.rfind("tie points: " + all + " of " + all + " inside", 0), 0u) << how;
  for (int axis = 0; axis < 3; ++axis) {
    const auto [low, high] = BulkAlong(block, axis);
    EXPECT_EQ(roi.min[axis], low) << axis;
    EXPECT_EQ(roi.max[axis], high) << axis;
  }
}

TEST(RegionChoice, GivenAndBlockRegionsWin) {
  ImageBlock block = BuildImageBlock(ObliqueScene());
  AddGroundTiePoints(&block);
  std::string how;
  RegionOfInterest given;
  given.min = Eigen::Vector3d(-1, -2, -3);
  given.max = Eigen::Vector3d(1, 2, 3);
  EXPECT_EQ(ChooseRegion(block, given, &how).max, given.max);
  EXPECT_EQ(how, "given");
  EXPECT_EQ(ChooseRegion(block, std::nullopt, &how).max, block.roi->max);
  EXPECT_EQ(how, "the block's");
  EXPECT_EQ(DescribeRegion(given), "x -1..1, y -2..2, z -3..3 m");
}

// The real sets: the facade from the street and the object all around keep nearly all
// their points (every image sees nearly every point); the kite aerials' region loses the
// fringe that a few frames reach.
TEST(RegionChoice, RealSets) {
  struct Case {
    const char* set;
    double min_share;  // of the points kept as well covered
    double max_area_ratio;  // new region's ground area (x * y) against all points' bulk
  };
  for (const Case& c : {Case{"strecha_fountain-P11/sparse_with_points", 0.9, 1.0},
                        Case{"middlebury_templeSparseRing/sparse_with_points", 0.99, 1.0},
                        Case{"boruszyn_kap/sparse_georef_local2180", 0.5, 0.5}}) {
    FACETS_SKIP_WITHOUT_SHARED_DATA(c.set);
    const ImageBlock block = ReadColmapModel(SharedDataDir() + c.set);
    std::string how;
    const RegionOfInterest roi = ChooseRegion(block, std::nullopt, &how);
    RegionOfInterest all;
    for (int axis = 0; axis < 3; ++axis) std::tie(all.min[axis], all.max[axis]) = BulkAlong(block, axis);
    std::printf("%s: all points %s; now %s (%s)\n", c.set, DescribeRegion(all).c_str(), DescribeRegion(roi).c_str(),
                how.c_str());
    int kept = 0, total = 0;
    ASSERT_EQ(std::sscanf(how.c_str(), "tie points: %d of %d", &kept, &total), 2) << how;
    EXPECT_GE(kept, c.min_share * total) << c.set;
    const Eigen::Vector3d size = roi.max - roi.min, size_all = all.max - all.min;
    EXPECT_LE(size.x() * size.y(), c.max_area_ratio * size_all.x() * size_all.y()) << c.set;
  }
}

}  // namespace
}  // namespace facets
