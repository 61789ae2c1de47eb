// WindowOccluders (engine/pipeline/window_occluders.h): one selection serves the window
// while its faces stay within the slack; a window that moved farther gets a new one.
#include "engine/pipeline/window_occluders.h"

#include <gtest/gtest.h>

#include <cmath>

#include "visibility/test_util.h"

namespace facets {
namespace {

TEST(WindowOccluders, SelectedAgainOnlyWhenTheWindowLeavesItsSlack) {
  // 40 m x 40 m of terrain (2 m cells), a 10 m building east of the window (the 8 m x 8 m
  // middle), seen by an oblique camera from beyond the building.
  FlatMesh mesh;
  AppendGridForTesting(-20, -20, 20, 20, 20, 20, [](double x, double y) { return 0.3 * std::sin(0.2 * x + 0.1 * y); },
                       &mesh);
  const int num_ground_faces = static_cast<int>(mesh.faces.size());
  AppendBoxForTesting({6, -4, -1}, {10, 4, 10}, false, &mesh);
  const Tessellation snapshot = TessellateFlatForTesting(mesh);
  const FaceBoxIndex surface(FaceBoxes(snapshot));
  const std::vector<Eigen::AlignedBox3d>& face_boxes = surface.faces();
  MeshWindow window;
  std::vector<Eigen::AlignedBox3d> window_boxes;
  for (int f = 0; f < num_ground_faces; ++f) {
    const Eigen::Vector3d c = (mesh.vertices[mesh.faces[f][0]] + mesh.vertices[mesh.faces[f][1]] +
                               mesh.vertices[mesh.faces[f][2]]) / 3.0;
    if (std::abs(c.x()) < 4 && std::abs(c.y()) < 4) {
      window.faces.push_back(f);
      window_boxes.push_back(face_boxes[f]);
    }
  }
  const Camera camera = Camera::Create(CameraModel::kPinhole, 400, 400, 200, 150, 400, 300);
  const std::vector<LevelImage> seeing = {{0, &camera, LookAtForTesting({45, 0, 35}, {0, 0, 0}), nullptr, nullptr}};
  WindowOccluders occluders(window, snapshot, surface, seeing, /*slack=*/1.0);

  auto shifted = [&](const Eigen::Vector3d& by) {
    std::vector<Eigen::AlignedBox3d> boxes;
    for (const Eigen::AlignedBox3d& b : window_boxes) boxes.emplace_back(b.min() + by, b.max() + by);
    return boxes;
  };
  const auto first = occluders.For(window_boxes);
  ASSERT_NE(first, nullptr);
  const size_t outside = (mesh.faces.size() - window.faces.size()) * kSubTrianglesPerFace;
  EXPECT_GT(first->NumTriangles(), size_t{0});
  EXPECT_LT(first->NumTriangles(), outside / 4);  // a cut, not the whole surroundings
  EXPECT_EQ(occluders.For(shifted({0.5, -0.5, 0.9})), first);
  EXPECT_EQ(occluders.selections(), 1);
  const auto moved = occluders.For(shifted({0, 0, -2.0}));
  EXPECT_NE(moved, first);
  EXPECT_EQ(occluders.selections(), 2);
}

}  // namespace
}  // namespace facets
