// Which faces of the surface around a window can hide part of the window from a
// camera (the window's occluders, engine/level_windows.cc): a face can stand between
// the projection centre and a window point only if its projection overlaps the
// window's projection and it is not entirely deeper (camera z) than the window there. Both
// tests work on boxes in the camera frame, in normalised (undistorted) coordinates,
// so they are conservative with or without lens distortion: every face that stops a
// ray which would otherwise reach the window is selected.
#pragma once

#include <Eigen/Geometry>
#include <vector>

#include "io/camera.h"
#include "io/rigid3d.h"
#include "mesh/tessellation.h"

namespace facets {

// Bounding box of each geometry face's tessellation points (its 16 sub-triangles, so
// the G1 bulge is included), in face order.
std::vector<Eigen::AlignedBox3d> FaceBoxes(const Tessellation& tessellation);

// A surface's face boxes and the same faces in spatial clusters (the cells of a grid of
// about 64 faces each), so that a selection tests a cluster's box before its faces.
class FaceBoxIndex {
 public:
  explicit FaceBoxIndex(std::vector<Eigen::AlignedBox3d> face_boxes);

  const std::vector<Eigen::AlignedBox3d>& faces() const { return faces_; }
  const std::vector<Eigen::AlignedBox3d>& cluster_boxes() const { return cluster_boxes_; }
  const std::vector<std::vector<int>>& clusters() const { return clusters_; }  // face indices, ascending

 private:
  std::vector<Eigen::AlignedBox3d> faces_;
  std::vector<Eigen::AlignedBox3d> cluster_boxes_;
  std::vector<std::vector<int>> clusters_;
};

struct OccluderView {
  const Camera* camera = nullptr;
  Rigid3d cam_from_world;
};

// Indices of the face boxes that can hide some point of a window from at least one
// view (ascending): per view, a 16 x 16 grid over the window's projection holds the
// deepest camera z of the window's face boxes, each grown by `slack` (object units) in
// every direction; a face is kept if its box reaches in front of that depth in a cell
// it overlaps, or reaches behind the camera's image plane. The selection holds for
// every window surface whose face boxes lie within the grown ones. The window's own
// faces, when among the surface's, come back too.
std::vector<int> FacesThatCanHide(const FaceBoxIndex& surface,
                                  const std::vector<Eigen::AlignedBox3d>& window_boxes, double slack,
                                  const std::vector<OccluderView>& views);

}  // namespace facets
