// Which faces of the surface around a window can hide part of the window from a
// camera (the window's occluders, engine/level_windows.cc): a face can stand between
// the projection centre and a window point only if its projection overlaps the
// window's projection and it is not entirely deeper (camera z) than the window. Both
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

struct OccluderView {
  const Camera* camera = nullptr;
  Rigid3d cam_from_world;
};

// Indices of the boxes that can hide some point of `target` from at least one view
// (ascending). A box reaching behind a camera's image plane is kept for that view.
std::vector<int> FacesThatCanHide(const std::vector<Eigen::AlignedBox3d>& face_boxes,
                                  const Eigen::AlignedBox3d& target,
                                  const std::vector<OccluderView>& views);

}  // namespace facets
