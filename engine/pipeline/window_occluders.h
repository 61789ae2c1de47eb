// The occluders of one window of a level (engine/pipeline/level_windows.cc): the faces of
// the level's surface outside the window that can stand between one of its images and
// the window (visibility/occluder_selection.h), as one Embree scene. They are selected
// for the window's faces grown by a slack and selected again only when the window's
// surface leaves that region during its runs: a face left out then could not hide any
// part of the window, so the window's observations are those of the whole surface.
#pragma once

#include <Eigen/Geometry>
#include <memory>
#include <vector>

#include "engine/images/level_image.h"
#include "mesh/tessellation.h"
#include "mesh/windows.h"
#include "visibility/embree_scene.h"
#include "visibility/occluder_selection.h"

namespace facets {

class WindowOccluders {
 public:
  // snapshot, surface (FaceBoxes(snapshot)): the level's surface around the window,
  // kept alive by the caller while the window runs; seeing: the window's images; slack:
  // how far (object units) the window's faces may move before the occluders are
  // selected again.
  WindowOccluders(const MeshWindow& window, const Tessellation& snapshot,
                  const FaceBoxIndex& surface, const std::vector<LevelImage>& seeing,
                  double slack);

  // The occluders for the window's faces as they stand (their boxes, the window's face
  // order; WindowAdjustment::OccluderSource); null when no face can hide the window.
  std::shared_ptr<const OccluderScene> For(const std::vector<Eigen::AlignedBox3d>& window_boxes);

  int selections() const { return selections_; }

 private:
  bool Covers(const std::vector<Eigen::AlignedBox3d>& window_boxes) const;
  void Select(const std::vector<Eigen::AlignedBox3d>& window_boxes);

  const Tessellation& snapshot_;
  const FaceBoxIndex& surface_;
  std::vector<char> in_window_;
  std::vector<OccluderView> views_;
  double slack_ = 0.0;
  std::vector<Eigen::AlignedBox3d> region_;  // the window's face boxes selected for, grown by slack_
  std::shared_ptr<const OccluderScene> scene_;
  int selections_ = 0;
};

}  // namespace facets
