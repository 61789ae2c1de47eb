// Visual hull: the volume whose every point projects into the object's
// silhouette (visibility/silhouette.h) in every image, carved in a voxel grid, and its
// boundary as a closed triangle mesh: a start for closed objects that, unlike an
// ellipsoid or the tie points' convex hull, already has the object's outline in every
// image (and its see-through gaps, where the images show them).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "io/camera.h"
#include "io/image_block.h"
#include "io/rigid3d.h"
#include "visibility/silhouette.h"

namespace facets {

struct VisualHullOptions {
  ForegroundOptions foreground = DefaultForeground();
  // Voxel edge (object units); 0 = the box's longest side / 200.
  double voxel_size = 0.0;
  // A voxel stays when at most this many images see background at its centre (a dark,
  // shaded part of the object under the threshold in one image does not carve it).
  int allowed_misses = 0;
  void Check() const;  // throws std::invalid_argument naming the option

  // Background at or below grey 15, a 1-pixel opening, the largest component, enclosed
  // holes under 500 pixels filled.
  static ForegroundOptions DefaultForeground();
};

struct VisualHullGrid {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();  // centre of voxel (0, 0, 0)
  double voxel = 0.0;
  Eigen::Vector3i size = Eigen::Vector3i::Zero();
  std::vector<uint8_t> inside;  // x fastest

  size_t Index(int i, int j, int k) const {
    return (static_cast<size_t>(k) * size.y() + j) * size.x() + i;
  }
  bool Inside(int i, int j, int k) const {
    return i >= 0 && j >= 0 && k >= 0 && i < size.x() && j < size.y() && k < size.z() &&
           inside[Index(i, j, k)] != 0;
  }
  Eigen::Vector3d Centre(int i, int j, int k) const {
    return origin + voxel * Eigen::Vector3d(i, j, k);
  }
  long long Count() const;
  Eigen::Vector3d Centroid() const;  // of the inside voxels
  double Volume() const { return static_cast<double>(Count()) * voxel * voxel * voxel; }
};

// Voxels per axis of the grid over `box` with edge `voxel` (at least 1; the last one may
// reach past the box).
Eigen::Vector3i VisualHullGridSize(const Eigen::AlignedBox3d& box, double voxel);

// The images a hull is carved from: camera, pose and foreground mask per image.
struct HullViews {
  std::vector<Camera> cameras;
  std::vector<Rigid3d> cam_from_world;
  std::vector<PixelMask> masks;
};

// The foreground masks of the block's image files (errors name the file).
HullViews ReadHullViews(const ImageBlock& block, const ForegroundOptions& foreground);

// Carves the grid over `box` with the given foreground masks (one per camera/pose, the
// camera's size). A voxel centre projecting outside an image or behind it counts as
// background there. Only the largest 6-connected inside component is kept.
VisualHullGrid CarveVisualHull(const std::vector<Camera>& cameras,
                               const std::vector<Rigid3d>& cam_from_world,
                               const std::vector<PixelMask>& masks,
                               const Eigen::AlignedBox3d& box, const VisualHullOptions& options);

// The same with the masks of the block's image files (errors name the file).
VisualHullGrid CarveVisualHull(const ImageBlock& block, const Eigen::AlignedBox3d& box,
                               const VisualHullOptions& options);

// The occupancy the mesh follows: the grid box-blurred 3x3x3, trilinear between voxel
// centres, 0 outside the grid; a point is inside the hull where it exceeds 1/2.
struct HullOccupancy {
  const VisualHullGrid* grid = nullptr;
  std::vector<float> smooth;
  double At(const Eigen::Vector3d& p) const;
  bool Inside(const Eigen::Vector3d& p) const { return At(p) > 0.5; }
};
HullOccupancy SmoothHullOccupancy(const VisualHullGrid& grid);

// Silhouette constraint: every point outside the hull is moved against its (outward)
// direction to the first position inside, searched in steps of a quarter voxel up to
// max_move and refined by bisection. Returns the points moved; *unresolved (optional)
// counts points outside with no inside position within max_move (left where they are).
int PullInsideHull(const HullOccupancy& occupancy, const std::vector<Eigen::Vector3d>& directions,
                   double max_move, std::vector<Eigen::Vector3d>* points, int* unresolved = nullptr);

// Rim attraction, the outward half of the silhouette constraint: an object touches its
// visual hull along its rims, where an image sees the surface edge-on at its silhouette.
// A point whose outward direction meets the hull's boundary within max_move is moved
// out onto the boundary when some image (a) sees background one voxel beyond that
// boundary point, so the boundary there is that image's silhouette cone, and (b) views
// the direction edge-on: |direction . viewing ray| <= max_cos. Points outside the hull
// are left alone (PullInsideHull). Returns the points moved.
int PushOntoHullRims(const HullOccupancy& occupancy, const HullViews& views,
                     const std::vector<Eigen::Vector3d>& directions, double max_move, double max_cos,
                     std::vector<Eigen::Vector3d>* points);

// The voxel of the finer hull a closed start holds the surface to after each level (the
// constraint hull, ClosedStartOptions::constraint_voxel), from the images when none is
// given: the images' pixel footprint at the carved box's centre (GroundPixel: median over the images of the
// distance from the projection centre over the focal length in pixels) times
// kConstraintVoxelFootprints. A voxel is kept or carved by the one mask pixel its centre
// projects to in each image, so a voxel of one footprint samples the silhouettes at their
// own resolution: coarser loses outline (the 3x3x3 blur of SmoothHullOccupancy erodes
// parts thinner than 2 voxels), finer adds voxels but no outline. No finer than the box
// holds in kMaxConstraintVoxels voxels: carving holds 5 bytes a voxel (the grid and the
// component labels), each constraint step 5 (the grid and its blurred occupancy), so at
// most 320 MB. No finer hull when that voxel is not finer than the start's.
inline constexpr double kConstraintVoxelFootprints = 1.0;
inline constexpr long long kMaxConstraintVoxels = 64'000'000;

struct ConstraintVoxelChoice {
  double voxel = 0.0;      // edge of the constraint hull's voxels (m); 0: the start's hull serves
  double footprint = 0.0;  // the images' pixel footprint at the box's centre (m)
  long long voxels = 0;    // of the grid over the box at `voxel` (0 when voxel is 0)
  std::string why;         // the rule and the figures in one line
};

// `given` > 0 wins (a hand-set voxel); `start_voxel`: the start hull's voxel (m).
ConstraintVoxelChoice ChooseConstraintVoxel(const ImageBlock& block, const Eigen::AlignedBox3d& box,
                                            double given, double start_voxel);

// Closed, manifold triangle mesh of the grid's boundary (CGAL surface mesher on the
// trilinear occupancy, level 1/2), triangles of about edge_length, normals outward.
// Throws std::runtime_error when the grid is empty or the mesher finds no surface.
void MeshVisualHull(const VisualHullGrid& grid, double edge_length,
                    std::vector<Eigen::Vector3d>* points, std::vector<Eigen::Vector3i>* triangles);

}  // namespace facets
