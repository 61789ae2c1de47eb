// Closed start surfaces for objects photographed from all around: instead of
// the 2.5D start plane, a closed TIN around the object, refined by the same engine.
//
// - Given: a start mesh file (PLY/OBJ, io/ply_io.h), used as it is; edges longer than
//   1.5x the coarsest level's edge length are split (mesh/local_ops.h QualityPass).
// - Automatic: an ellipsoid fitted robustly to the tie points (a sphere first, by
//   iteratively re-weighted least squares with Tukey weights on the distance to it,
//   starting from the point the cameras' optical axes meet; then a general ellipsoid
//   from the sphere's inliers, re-weighted the same way). Points of a floor or of a
//   background the object stands before are far from any ellipsoid through the object
//   and get weight 0. Triangulated as a geodesic ellipsoid with the coarsest level's
//   edge length (mesh/closed_surface.h).
// - Or the convex hull of those inlier tie points, grown a little (ClosedStartOptions::
//   shape "hull"), for objects far from an ellipsoid (a temple, a box).
// - Or the visual hull (shape "visual-hull", visibility/visual_hull.h): the region of
//   interest grown by visual_hull_grow on every side, carved to the images'
//   background-thresholded silhouettes, meshed with the coarsest level's edge length:
//   a start that projects onto the object's outline in every image.
// - Object lifting along the normals: the start scaled about its centre over a range
//   of factors, one iteration each on the coarsest level; chosen by the sign change of
//   the mean displacement (outward -> inward) and, among those, the smallest sigma0.
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "engine/solver/adjustment_options.h"
#include "engine/solver/window_adjustment.h"
#include "io/image_block.h"
#include "mesh/closed_surface.h"
#include "mesh/local_ops.h"
#include "mesh/tin.h"
#include "engine/start/visual_hull.h"

namespace facets {

struct LiftingTrial;

struct EllipsoidFit {
  Ellipsoid ellipsoid;
  bool is_sphere = false;   // the general fit failed or was implausible
  int points = 0;           // tie points offered
  int inliers = 0;          // with weight > 0 in the final fit
  double rms_distance = 0;  // of the inliers to the ellipsoid (radial), m
  std::vector<bool> inlier;  // per point offered
};

// The least-squares meeting point of the images' optical axes (the volume the cameras
// look at). Throws std::runtime_error for fewer than 2 images or parallel axes.
Eigen::Vector3d CameraAxesMeet(const ImageBlock& block);

// Robust ellipsoid through `points` (>= 10), starting from `centre_guess`.
// Throws std::runtime_error when too few points remain.
EllipsoidFit FitStartEllipsoid(const std::vector<Eigen::Vector3d>& points,
                               const Eigen::Vector3d& centre_guess);

struct ClosedStartOptions {
  // Start mesh file; empty: the shape fitted to the tie points.
  std::string mesh_file;
  // Automatic start: "ellipsoid" (fitted) or "hull" (convex hull of the ellipsoid
  // fit's inlier tie points, grown by hull_inflate, for boxy objects).
  std::string shape = "ellipsoid";
  double hull_inflate = 0.05;
  // shape "visual-hull": silhouettes, voxel size, misses; the carved box is the region
  // of interest grown by this share of its size on every side.
  VisualHullOptions visual_hull;
  double visual_hull_grow = 0.25;
  // Visual-hull start: after each level's adjustment, vertices outside the hull are
  // moved inward along their normals onto it (at most hull_clamp_edges edge lengths):
  // a background pixel of any image says the object is not there, but it gives no
  // observation, so nothing else stops the surface from swelling past the silhouettes.
  bool hull_clamp = true;
  double hull_clamp_edges = 2.0;
  // And outward (PushOntoHullRims): vertices inside whose outward normal meets the hull
  // within hull_rim_edges edge lengths where an image sees the surface edge-on
  // (|normal . ray| <= hull_rim_cos) and background just beyond are moved onto the hull:
  // the object touches its hull along the rims, and nothing else pulls the outline out.
  // Off by default: it raises the silhouette IoU (temple median 0.896 -> 0.906) but holds
  // the surface to the hull between the views' rims, after the finest level's last
  // adjustment (synthetic blob: object median 0.05 -> 0.27 GSD).
  bool hull_rims = false;
  // Voxel edge of the hull these constraints use (m; 0 = from the images,
  // ChooseConstraintVoxel): a finer hull keeps thin parts the start's 3x3x3-blurred
  // voxels erode, without the mesher following its detail on the coarsest level.
  double constraint_voxel = 0.0;
  // The inward pull halved, at last undone, where it folds a face or makes faces cross.
  // Off by default: on the synthetic blob the undone pulls leave spikes outside the hull
  // (71 vertices, IoU min 0.895, p90 1.7 GSD); on the temple it takes the crossing pairs
  // left from 45-83 to 0 with the rim push and the fine constraint hull in 2 of 3 runs
  // (146 in the third).
  bool clamp_guard = false;
  double hull_rim_edges = 1.0;
  double hull_rim_cos = 0.5;
  // When not empty, the start mesh (after object lifting) is written here as PLY.
  std::string write_start;
  // Object lifting: scale factors over 1 +- range / 2 in `steps` steps; 0 steps = off.
  int lifting_steps = 0;
  double lifting_range = 0.4;
  void Check() const;  // throws std::invalid_argument naming the option
};

// What the start is made from, decided before the pyramid (its centre sets the
// ground pixel and so the edge lengths).
struct ClosedStart {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  std::optional<EllipsoidFit> fit;    // automatic start
  std::optional<TinMesh> given;       // start mesh file
  DegenerateRepairReport given_repair;  // its triangles of no area (mesh/local_ops.h)
  std::vector<Eigen::Vector3d> hull_points;  // shape "hull": the fit's inliers
  std::optional<VisualHullGrid> visual_hull;  // shape "visual-hull"
  std::optional<HullViews> hull_views;        // the masks it was carved from (kept for hull_rims)
  std::optional<VisualHullGrid> constraint_hull;  // finer, ClosedStartOptions::constraint_voxel
  std::optional<ConstraintVoxelChoice> constraint_voxel;  // how its voxel was chosen (visual hull)
  const VisualHullGrid* ConstraintHull() const {
    return constraint_hull ? &*constraint_hull : visual_hull ? &*visual_hull : nullptr;
  }
  std::string Describe() const;
};

// Reads the start mesh, or fits the ellipsoid to the block's tie points inside `roi`
// (all tie points when fewer than 10 lie inside). Errors name the file or say what is
// missing.
ClosedStart PrepareClosedStart(const ImageBlock& block, const RegionOfInterest& roi,
                               const ClosedStartOptions& options);

// The coarsest level's start TIN: the given mesh (long edges split) or the geodesic
// ellipsoid with `edge_length`, then object lifting when options.lifting_steps > 0
// (`images`: the coarsest level; `one`: its adjustment options). Every trial goes into
// *trials (LiftingTrial::height holds the scale factor). Vertex normals set.
TinMesh MakeClosedStartMesh(const ClosedStart& start, const ClosedStartOptions& options,
                            double edge_length, const std::vector<LevelImage>& images,
                            const AdjustmentOptions& one, std::vector<LiftingTrial>* trials,
                            const std::function<void(const std::string&)>& say);

// The silhouette constraint (ClosedStartOptions::hull_clamp) on `mesh` (vertex normals
// updated); nothing when the start is no visual hull. Returns the vertices moved;
// *unresolved: vertices outside with no inside position within max_move.
// guard: pulls that fold a face or make two faces cross are halved, at last undone.
int ClampToVisualHull(const ClosedStart& start, double max_move, TinMesh* mesh, int* unresolved,
                      bool guard = false);

// The outward half (ClosedStartOptions::hull_rims) on `mesh` (vertex normals updated);
// nothing when the start is no visual hull. Pushes that fold a face or make two faces
// cross are halved, at last undone (LimitFoldingSteps). Returns the vertices moved.
int PushOntoVisualHullRims(const ClosedStart& start, double max_move, double max_cos, TinMesh* mesh);

}  // namespace facets
