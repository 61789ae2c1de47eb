#include "engine/pipeline/window_occluders.h"

namespace facets {

WindowOccluders::WindowOccluders(const MeshWindow& window, const Tessellation& snapshot,
                                 const FaceBoxIndex& surface, const std::vector<LevelImage>& seeing,
                                 double slack)
    : snapshot_(snapshot), surface_(surface), in_window_(surface.faces().size(), 0), slack_(slack) {
  for (int f : window.faces) in_window_[f] = 1;
  for (const LevelImage& image : seeing) views_.push_back({image.camera, image.cam_from_world});
}

std::shared_ptr<const OccluderScene> WindowOccluders::For(const std::vector<Eigen::AlignedBox3d>& window_boxes) {
  if (selections_ == 0 || !Covers(window_boxes)) Select(window_boxes);
  return scene_;
}

bool WindowOccluders::Covers(const std::vector<Eigen::AlignedBox3d>& window_boxes) const {
  if (window_boxes.size() != region_.size()) return false;
  for (size_t f = 0; f < window_boxes.size(); ++f) {
    if (!window_boxes[f].isEmpty() && !region_[f].contains(window_boxes[f])) return false;
  }
  return true;
}

void WindowOccluders::Select(const std::vector<Eigen::AlignedBox3d>& window_boxes) {
  ++selections_;
  const Eigen::Vector3d grow = Eigen::Vector3d::Constant(slack_);
  region_.clear();
  for (const Eigen::AlignedBox3d& box : window_boxes) {
    region_.push_back(box.isEmpty() ? box : Eigen::AlignedBox3d(box.min() - grow, box.max() + grow));
  }
  // The selected faces' sub-triangles, with their own points.
  std::vector<Eigen::Vector3d> points;
  std::vector<Eigen::Vector3i> triangles;
  std::vector<int> point_index(snapshot_.points.size(), -1);
  for (int f : FacesThatCanHide(surface_, window_boxes, slack_, views_)) {
    if (in_window_[f]) continue;
    for (int s = f * kSubTrianglesPerFace; s < (f + 1) * kSubTrianglesPerFace; ++s) {
      Eigen::Vector3i tri;
      for (int c = 0; c < 3; ++c) {
        int& index = point_index[snapshot_.triangles[s][c]];
        if (index < 0) {
          index = static_cast<int>(points.size());
          points.push_back(snapshot_.points[snapshot_.triangles[s][c]]);
        }
        tri[c] = index;
      }
      triangles.push_back(tri);
    }
  }
  scene_ = triangles.empty() ? nullptr
                             : std::make_shared<const OccluderScene>(EmbreeDevice::Shared(), points, triangles);
}

}  // namespace facets
