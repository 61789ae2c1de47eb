// Whether a point lies in front of an image and projects into its frame (no occlusion:
// no surface is known). Used before any work on the block: the geometry check and the
// region chosen from the tie points.
#pragma once

#include <Eigen/Core>

#include "io/camera.h"
#include "io/image_block.h"

namespace facets {

class ImageFrame {
 public:
  // The camera must outlive the frame.
  explicit ImageFrame(const Camera& camera);
  bool Contains(const BlockImage& image, const Eigen::Vector3d& point) const;

 private:
  const Camera* camera_;
  // The frame as undistorted normalised coordinates (x/z, y/z): the box of its border's
  // rays, widened by 1 %. Points outside it are not projected through the lens model,
  // whose polynomial may fold them back into the frame.
  Eigen::Vector2d min_, max_;
};

}  // namespace facets
