// Per-pixel first-hit ray casting (DESIGN.md section 4, "Visibility"): one ray per
// pixel from the projection centre through the pixel centre (lens distortion
// removed), first intersection with the tessellated surface only = a per-pixel
// distance buffer. Rays go to Embree in packets of 16 (rtcIntersect16, 4x4 pixel
// blocks, coherent context), TBB spreads image tiles over threads.
//
// Units and frames: pixel (x, y) is the integer pixel index, its centre is at
// (x + 0.5, y + 0.5) (io/camera.h); rays start at the projection centre in local
// object coordinates with a unit direction, so distances are in object units (m).
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "io/camera.h"
#include "io/image_block.h"
#include "io/rigid3d.h"
#include "visibility/surface_scene.h"

namespace facets {

// Half-open pixel rectangle [x0, x1) x [y0, y1) of pixel indices.
struct PixelRect {
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;

  static PixelRect Full(const Camera& camera) { return {0, 0, camera.width, camera.height}; }
  int Width() const { return x1 > x0 ? x1 - x0 : 0; }
  int Height() const { return y1 > y0 ? y1 - y0 : 0; }
  long long Area() const { return static_cast<long long>(Width()) * Height(); }
  bool Empty() const { return Width() == 0 || Height() == 0; }
  bool Contains(int x, int y) const { return x >= x0 && x < x1 && y >= y0 && y < y1; }
  PixelRect Intersection(const PixelRect& other) const;
  bool operator==(const PixelRect&) const = default;
};

enum class RayStatus : uint8_t {
  kObservation = 0,  // front-facing first hit at a usable angle
  kMiss,             // the ray leaves the scene
  kBackFace,         // first hit on a back face (ray direction . facet normal > 0)
  kGrazing,          // |cos incidence| below CastOptions::min_cos_incidence
  kOccluded,         // first hit on an occluder (SurfaceScene::SetOccluders)
};

// One pixel's first hit, 40 bytes. Face barycentrics are float: they are mapped from
// Embree's float (u, v) and double storage would add bytes, not accuracy.
struct PixelObservation {
  int32_t x = 0, y = 0;  // pixel indices; the ray goes through (x + 0.5, y + 0.5)
  int32_t face = -1;     // geometry triangle = facet / 16 (-1 on a miss)
  int32_t facet = -1;    // sub-triangle = grey facet index s = Embree primitive id
  float b1 = 0, b2 = 0;  // face barycentrics of vertices 1, 2 (t1, t2); b0 = 1-b1-b2
  float u = 0, v = 0;    // grey facet barycentrics (t~1, t~2) on triangles[facet]
  float distance = 0;    // from the projection centre along the unit ray, object units
  float cos_incidence = 0;  // |cos| of the angle between ray and facet normal
  RayStatus status = RayStatus::kMiss;

  bool valid() const { return status == RayStatus::kObservation; }
  Eigen::Vector3d FaceBarycentrics() const { return {1.0 - b1 - b2, b1, b2}; }
};

struct CastOptions {
  // Rays with |cos incidence| below this are no observation: at grazing incidence a
  // pixel's footprint smears over a long strip of surface and the observation
  // equation divides by d . N, which goes to zero. 0.1 = 84.3 degrees off the normal.
  double min_cos_incidence = 0.1;
  // A first hit on a back face is no observation (it still occludes what lies
  // behind). Off only for open surfaces seen from both sides.
  bool cull_back_faces = true;
  // false: return valid observations only (what the engine wants); true: one entry
  // per pixel of the pixel set, status says why a pixel is not an observation.
  bool keep_invalid = false;
  // Side of the square image tiles handed to TBB, in pixels; a multiple of 4 keeps
  // the 4x4 packets full. 32 gives ~64 packets per task: enough to amortise
  // scheduling, small enough to balance 2-64 threads on one image.
  int tile_size = 32;

  // Throws std::invalid_argument on a value out of range.
  void Check() const;
};

struct CastStats {
  long long rays = 0;
  long long observations = 0;
  long long misses = 0;
  long long back_faces = 0;
  long long grazing = 0;
  long long occluded = 0;
};

struct CastResult {
  // Ordered by tile, then by 4x4 block, then row-major within the block
  // (deterministic, independent of the thread count).
  std::vector<PixelObservation> observations;
  CastStats stats;
};

// Unit ray directions (world = local object frame) for the pixels of one image:
// R^T * CamFromImage(x + 0.5, y + 0.5), normalised. Without distortion this is one
// 3x3 product per pixel; with distortion, the per-pixel Newton inversion of
// Camera::Undistort.
class PixelRays {
 public:
  PixelRays(const Camera& camera, const Rigid3d& cam_from_world);

  const Eigen::Vector3d& origin() const { return origin_; }
  Eigen::Vector3d Direction(int x, int y) const;

 private:
  Camera camera_;
  bool distorted_ = false;
  Eigen::Matrix3d world_from_cam_;
  Eigen::Matrix3d world_from_pixel_;  // R^T K^-1 for the undistorted case
  Eigen::Vector3d origin_;
};

// First hits for all pixels of `rect` (clipped to the image).
CastResult CastPixels(const SurfaceScene& scene, const Camera& camera,
                      const Rigid3d& cam_from_world, const PixelRect& rect,
                      const CastOptions& options = {});
// First hits for the pixels of a list of rectangles (each clipped to the image;
// e.g. the 8x8 blocks of ProjectedBlocks in visibility/image_selection.h), in
// rectangle order; the rectangles should not overlap (a pixel would be cast twice).
CastResult CastPixels(const SurfaceScene& scene, const Camera& camera,
                      const Rigid3d& cam_from_world, const std::vector<PixelRect>& rects,
                      const CastOptions& options = {});
// First hits for a list of pixel indices (outside-image pixels are skipped).
CastResult CastPixels(const SurfaceScene& scene, const Camera& camera,
                      const Rigid3d& cam_from_world,
                      const std::vector<Eigen::Vector2i>& pixels,
                      const CastOptions& options = {});
// Convenience: image `image_index` of `block`.
CastResult CastPixels(const SurfaceScene& scene, const ImageBlock& block,
                      int image_index, const PixelRect& rect,
                      const CastOptions& options = {});

}  // namespace facets
