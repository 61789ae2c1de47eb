// Window/image selection by bounding volumes (DESIGN.md section 2: "which images can
// see a window is decided first by bounding volumes"), and a bounding volume
// hierarchy over geometry faces for "faces in a region" queries.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <optional>
#include <vector>

#include "io/camera.h"
#include "io/image_block.h"
#include "io/rigid3d.h"
#include "mesh/tessellation.h"
#include "visibility/pixel_cast.h"

namespace facets {

// The pixel rectangle (clipped to the image, grown by margin_px) covering the
// projection of `box`, or nullopt when the box is entirely behind the camera or
// projects outside the image. Conservative: a box that reaches behind the projection
// centre's image plane gets the whole image. Without distortion the projection of a
// box in front of the camera is the convex hull of its 8 projected corners, so the
// rectangle is exact; with distortion the box's normalised-coordinate rectangle is
// clipped to the image's field of view and its boundary distorted at 16 points per
// side (hence the margin).
std::optional<PixelRect> ProjectBox(const Eigen::AlignedBox3d& box, const Camera& camera,
                                    const Rigid3d& cam_from_world, int margin_px = 2);

// The block_size x block_size pixel blocks (aligned to multiples of block_size, clipped
// to `clip`) onto which at least one of the boxes projects (ProjectBox with margin_px),
// row-major. With the boxes of a window's faces (FaceBoxes in
// visibility/occluder_selection.h) every pixel whose ray can hit the window lies in a
// returned block; casting only those skips the parts of the window's rectangle that
// only the surroundings cover (an oblique view's rectangle of a tall window is mostly
// empty). With lens distortion (ProjectBox samples every box border, too slow per face)
// the union of the boxes is projected instead: all blocks of that rectangle.
std::vector<PixelRect> ProjectedBlocks(const std::vector<Eigen::AlignedBox3d>& boxes,
                                       const Camera& camera, const Rigid3d& cam_from_world,
                                       const PixelRect& clip, int block_size = 8, int margin_px = 1);

struct ImageSelection {
  int image_index = 0;  // into ImageBlock::images
  int image_id = 0;
  PixelRect rect;       // pixels onto which the box projects
};

// Images of `block` whose view the box overlaps, in block order.
std::vector<ImageSelection> SelectImages(const Eigen::AlignedBox3d& box,
                                         const ImageBlock& block, int margin_px = 2);

// First hits of every pixel onto which `box` projects, for every image that sees it
// (SelectImages + CastPixels on the rectangle). Observations on faces outside the
// window are kept: the caller decides (they occlude, and neighbours may want them).
struct ImageCast {
  ImageSelection selection;
  CastResult cast;
};
std::vector<ImageCast> CastWindow(const SurfaceScene& scene, const ImageBlock& block,
                                  const Eigen::AlignedBox3d& box,
                                  const CastOptions& options = {}, int margin_px = 2);

// Bounding box of the tessellation points of the given geometry faces (the rendered
// surface, so G1 bulges are included).
Eigen::AlignedBox3d FacesBoundingBox(const Tessellation& tessellation,
                                     const std::vector<int>& faces);

// Static BVH (median split on the longest axis, leaves of up to 4 faces) over the
// bounding boxes of the geometry faces of a tessellation. Rebuild it when the surface
// changed; queries are thread-safe.
class FaceBvh {
 public:
  explicit FaceBvh(const Tessellation& tessellation);

  // Faces whose bounding box overlaps `box`, ascending.
  std::vector<int> FacesInBox(const Eigen::AlignedBox3d& box) const;
  const Eigen::AlignedBox3d& FaceBox(int face) const { return face_boxes_[face]; }
  int NumFaces() const { return static_cast<int>(face_boxes_.size()); }

 private:
  struct Node {
    Eigen::AlignedBox3d box;
    int first = 0, count = 0;  // leaf: faces order_[first, first + count)
    int left = -1, right = -1;
  };
  int Build(int first, int count);

  std::vector<Eigen::AlignedBox3d> face_boxes_;
  std::vector<int> order_;
  std::vector<Node> nodes_;
};

}  // namespace facets
