// FacesThatCanHide (visibility/occluder_selection.h) on a real Embree scene: every
// face that is the first hit of a pixel ray which would otherwise reach the window
// must be selected; and the selection must be a real cut of the surroundings.
#include "visibility/occluder_selection.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <iostream>
#include <set>

#include "visibility/image_selection.h"
#include "visibility/pixel_cast.h"
#include "visibility/surface_scene.h"
#include "visibility/test_util.h"

namespace facets {
namespace {

struct HiderCount {
  size_t selected = 0;       // faces selected, the window's own included
  int num_faces = 0;
  long long window_rays = 0;  // rays that reach the window
  long long hidden = 0;       // of them first stopped by another face
  long long missing = 0;      // ... by a face that was not selected
};

// 60 m x 60 m wavy terrain of 2 m cells and a few buildings, one of them right next to
// the window (a 12 m x 12 m patch of terrain in the middle), seen by six views. The
// occluders are selected for the window as it stands with `slack`; the rays are cast
// with the window lifted by `lift` (m).
HiderCount CountHiders(double slack, double lift) {
  FlatMesh mesh;
  auto height = [](double x, double y) { return 0.8 * std::sin(0.15 * x) + 0.5 * std::cos(0.2 * y); };
  AppendGridForTesting(-30, -30, 30, 30, 30, 30, height, &mesh);
  const int num_ground_faces = static_cast<int>(mesh.faces.size());
  AppendBoxForTesting({7, -4, -1}, {12, 4, 9}, false, &mesh);
  AppendBoxForTesting({-4, -14, -1}, {4, -8, 12}, false, &mesh);
  AppendBoxForTesting({-20, 15, -1}, {-12, 22, 15}, false, &mesh);
  AppendBoxForTesting({18, -25, -1}, {25, -18, 6}, false, &mesh);
  const int num_faces = static_cast<int>(mesh.faces.size());
  const std::vector<Eigen::AlignedBox3d> boxes = FaceBoxes(TessellateFlatForTesting(mesh));

  // The window with its own (lifted) vertices; `moved`: the surroundings and the window.
  std::vector<char> in_window(num_faces, 0);
  FlatMesh window, moved = mesh;
  std::vector<Eigen::AlignedBox3d> window_boxes;
  window.vertices = mesh.vertices;
  for (Eigen::Vector3d& v : window.vertices) v.z() += lift;
  for (int f = 0; f < num_ground_faces; ++f) {
    const Eigen::Vector3d c = (mesh.vertices[mesh.faces[f][0]] + mesh.vertices[mesh.faces[f][1]] +
                               mesh.vertices[mesh.faces[f][2]]) / 3.0;
    if (std::abs(c.x()) < 6 && std::abs(c.y()) < 6) {
      in_window[f] = 1;
      window.faces.push_back(mesh.faces[f]);
      window_boxes.push_back(boxes[f]);
      const int base = static_cast<int>(moved.vertices.size());
      for (int k = 0; k < 3; ++k) moved.vertices.push_back(window.vertices[mesh.faces[f][k]]);
      moved.faces[f] = Eigen::Vector3i(base, base + 1, base + 2);
    }
  }

  const Camera camera = Camera::Create(CameraModel::kPinhole, 300, 300, 160, 120, 320, 240);
  std::vector<OccluderView> views;
  std::vector<Rigid3d> poses = {LookAtForTesting({0, 0, 60}, {0, 0, 0}),      LookAtForTesting({-40, 0, 40}, {0, 0, 0}),
                                LookAtForTesting({40, 5, 35}, {0, 0, 0}),     LookAtForTesting({0, -45, 30}, {0, 0, 0}),
                                LookAtForTesting({5, 40, 30}, {0, 2, 0}),     LookAtForTesting({30, 30, 50}, {10, 10, 0})};
  for (const Rigid3d& pose : poses) views.push_back({&camera, pose});
  const std::vector<int> selected = FacesThatCanHide(FaceBoxIndex(boxes), window_boxes, slack, views);
  const std::set<int> selected_set(selected.begin(), selected.end());

  const SurfaceScene whole(TessellateFlatForTesting(moved), /*refittable=*/false);
  const SurfaceScene window_only(TessellateFlatForTesting(window), /*refittable=*/false);
  CastOptions options;
  options.keep_invalid = true;
  options.cull_back_faces = false;
  options.min_cos_incidence = 0.0;
  HiderCount count;
  count.selected = selected.size();
  count.num_faces = num_faces;
  for (const Rigid3d& pose : poses) {
    const CastResult a = CastPixels(whole, camera, pose, PixelRect::Full(camera), options);
    const CastResult b = CastPixels(window_only, camera, pose, PixelRect::Full(camera), options);
    EXPECT_EQ(a.observations.size(), b.observations.size());
    for (size_t i = 0; i < a.observations.size() && i < b.observations.size(); ++i) {
      if (b.observations[i].status == RayStatus::kMiss) continue;  // the ray does not reach the window
      ++count.window_rays;
      const int face = a.observations[i].face;
      if (face < 0 || in_window[face]) continue;
      ++count.hidden;
      count.missing += !selected_set.count(face);
    }
  }
  std::cout << "occluder selection, slack " << slack << " m, window lifted " << lift << " m: " << count.selected
            << " of " << num_faces << " faces selected, " << count.window_rays << " rays reach the window, "
            << count.hidden << " of them hidden, " << count.missing << " by unselected faces\n";
  return count;
}

TEST(OccluderSelection, EveryFaceThatHidesTheWindowIsSelected) {
  const HiderCount still = CountHiders(0.0, 0.0);
  EXPECT_GT(still.hidden, 1000);
  EXPECT_EQ(still.missing, 0);
  EXPECT_LT(still.selected, static_cast<size_t>(still.num_faces) / 4);
}

// A selection holds for the window anywhere within its slack; a window sunk farther is
// hidden by faces the selection left out.
TEST(OccluderSelection, SelectionHoldsWithinTheSlack) {
  const HiderCount within = CountHiders(2.0, -1.5);
  EXPECT_GT(within.hidden, 1000);
  EXPECT_EQ(within.missing, 0);
  const HiderCount beyond = CountHiders(0.0, -3.0);
  EXPECT_GT(beyond.missing, 0);
}

// ProjectedBlocks (visibility/image_selection.h) with the boxes of a window's faces:
// every pixel whose ray hits the window lies in a selected 8x8 block, and casting the
// blocks gives exactly the observations of casting the window's whole rectangle.
TEST(ProjectedBlocks, EveryPixelThatHitsTheWindowIsInABlock) {
  // A wavy 20 m x 20 m window with a 6 m tower on it, seen from oblique views.
  FlatMesh window;
  AppendGridForTesting(-10, -10, 10, 10, 10, 10,
                       [](double x, double y) { return 0.8 * std::sin(0.3 * x) + 0.5 * std::cos(0.4 * y); }, &window);
  AppendBoxForTesting({-2, -2, -1}, {2, 2, 6}, false, &window);
  const Tessellation tess = TessellateFlatForTesting(window);
  const SurfaceScene scene(tess, /*refittable=*/false);
  const std::vector<Eigen::AlignedBox3d> boxes = FaceBoxes(tess);
  Eigen::AlignedBox3d all;
  for (const auto& b : boxes) all.extend(b);
  const Camera camera = Camera::Create(CameraModel::kPinhole, 500, 500, 320, 240, 640, 480);
  long long hits = 0, outside = 0, blocks_total = 0, blocks_rect = 0;
  for (const Rigid3d& pose : {LookAtForTesting({0, 0, 40}, {0, 0, 0}), LookAtForTesting({-35, 5, 25}, {0, 0, 0}),
                              LookAtForTesting({20, -30, 20}, {3, 0, 0}), LookAtForTesting({10, 25, 15}, {0, 0, 2})}) {
    const auto rect = ProjectBox(all, camera, pose);
    ASSERT_TRUE(rect.has_value());
    const std::vector<PixelRect> blocks = ProjectedBlocks(boxes, camera, pose, *rect);
    blocks_total += static_cast<long long>(blocks.size());
    blocks_rect += ((rect->x1 + 7) / 8 - rect->x0 / 8) * ((rect->y1 + 7) / 8 - rect->y0 / 8);
    std::vector<char> in_block(static_cast<size_t>(camera.width) * camera.height, 0);
    for (const PixelRect& b : blocks) {
      for (int y = b.y0; y < b.y1; ++y)
        for (int x = b.x0; x < b.x1; ++x) in_block[static_cast<size_t>(y) * camera.width + x] = 1;
    }
    CastOptions options;
    options.keep_invalid = true;
    const CastResult full = CastPixels(scene, camera, pose, PixelRect::Full(camera), options);
    for (const PixelObservation& obs : full.observations) {
      if (obs.status == RayStatus::kMiss) continue;
      ++hits;
      outside += !in_block[static_cast<size_t>(obs.y) * camera.width + obs.x];
    }
    // Valid observations: the same, pixel for pixel (both sorted by pixel).
    const CastResult a = CastPixels(scene, camera, pose, *rect);
    const CastResult b = CastPixels(scene, camera, pose, blocks);
    auto key = [&](const PixelObservation& o) { return static_cast<long long>(o.y) * camera.width + o.x; };
    std::vector<std::pair<long long, int>> ka, kb;
    for (const auto& o : a.observations) ka.emplace_back(key(o), o.facet);
    for (const auto& o : b.observations) kb.emplace_back(key(o), o.facet);
    std::sort(ka.begin(), ka.end());
    std::sort(kb.begin(), kb.end());
    EXPECT_EQ(ka, kb);
  }
  std::cout << "projected blocks: " << blocks_total << " of " << blocks_rect << " blocks of the window rectangles, "
            << hits << " pixels hit the window, " << outside << " outside the blocks\n";
  EXPECT_GT(hits, 100000);
  EXPECT_EQ(outside, 0);
  EXPECT_LT(blocks_total, blocks_rect);
}

// Every face in exactly one cluster, inside its cluster's box; clusters of tens of faces.
TEST(FaceBoxIndex, ClustersPartitionTheFaces) {
  FlatMesh mesh;
  AppendGridForTesting(-50, -30, 50, 30, 100, 60, [](double x, double y) { return 0.5 * std::sin(0.1 * x * y); }, &mesh);
  AppendBoxForTesting({-4, -4, -1}, {4, 4, 40}, false, &mesh);  // a tower
  const FaceBoxIndex index(FaceBoxes(TessellateFlatForTesting(mesh)));
  std::vector<int> seen(mesh.faces.size(), 0);
  for (size_t c = 0; c < index.clusters().size(); ++c) {
    for (int f : index.clusters()[c]) {
      ++seen[f];
      EXPECT_TRUE(index.cluster_boxes()[c].contains(index.faces()[f]));
    }
  }
  EXPECT_EQ(std::count(seen.begin(), seen.end(), 1), static_cast<long>(mesh.faces.size()));
  const double mean = static_cast<double>(mesh.faces.size()) / static_cast<double>(index.clusters().size());
  std::cout << index.clusters().size() << " clusters of " << mesh.faces.size() << " faces, " << mean << " each\n";
  EXPECT_GT(mean, 16.0);
  EXPECT_LT(mean, 256.0);
  // Faces along a 1 km line: at most 1025 cells along it.
  std::vector<Eigen::AlignedBox3d> line;
  for (int i = 0; i < 5000; ++i) line.emplace_back(Eigen::Vector3d(0.2 * i, 0, 0), Eigen::Vector3d(0.2 * i + 0.1, 0, 0));
  const FaceBoxIndex line_index(line);
  EXPECT_LE(line_index.clusters().size(), size_t{1025});
  EXPECT_GE(line_index.clusters().size(), size_t{1000});
}

// Without views nothing can hide anything; a box behind every camera neither.
TEST(OccluderSelection, NothingWithoutViews) {
  std::vector<Eigen::AlignedBox3d> boxes = {Eigen::AlignedBox3d(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 1, 1))};
  EXPECT_TRUE(FacesThatCanHide(FaceBoxIndex(boxes), boxes, 0.0, {}).empty());
  const Camera camera = Camera::Create(CameraModel::kPinhole, 300, 300, 160, 120, 320, 240);
  const Rigid3d pose = LookAtForTesting({0, 0, 50}, {0, 0, 100});  // looks up, away from the boxes
  EXPECT_TRUE(FacesThatCanHide(FaceBoxIndex(boxes), boxes, 0.0, {{&camera, pose}}).empty());
}

}  // namespace
}  // namespace facets
