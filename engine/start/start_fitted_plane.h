// A start plane of any orientation, fitted to the tie points by robust total least
// squares (a facade seen from the street is far from the horizontal start
// plane the engine uses for aerial blocks).
//
// The fit: the plane through the centroid with the normal of the smallest eigenvalue
// of the points' scatter matrix (orthogonal distances, so any orientation is fitted
// alike); then, for a few rounds, points whose distance exceeds k x 1.4826 x MAD of the
// distances are dropped and the plane is fitted again to the rest. The start TIN is the
// regular grid of MakeStartGrid laid into that plane over the 2nd..98th percentile
// extent of the kept points, normals turned towards the cameras.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "engine/start/start_tiepoints.h"
#include "mesh/tin.h"

namespace facets {

struct FittedPlaneOptions {
  double rejection_k = 3.0;  // drop points beyond k robust sigmas (1.4826 x MAD)
  int rounds = 5;            // refits after rejection
  double extent_quantile = 0.02;  // extent from this to 1 - this quantile of kept points
  int min_points = 10;
};

struct FittedPlane {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();  // centroid of the kept points
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
  // In-plane axes; axis_u x axis_v = normal (so grid faces face along the normal).
  Eigen::Vector3d axis_u = Eigen::Vector3d::UnitX();
  Eigen::Vector3d axis_v = Eigen::Vector3d::UnitY();
  Eigen::Vector2d min_uv = Eigen::Vector2d::Zero();  // extent in (u, v) about centre
  Eigen::Vector2d max_uv = Eigen::Vector2d::Zero();
  double rms = 0.0;       // orthogonal distance RMS of the kept points
  int kept = 0;           // points kept after rejection
  int total = 0;
  // Angle between the normal and +Z (0 = horizontal plane, 90 = vertical wall).
  double tilt_deg = 0.0;
};

// Throws std::runtime_error when fewer than min_points points are given or they are
// (nearly) collinear. `viewpoint` (e.g. the mean projection centre) decides the sign of
// the normal: it points to the viewpoint's side.
FittedPlane FitStartPlane(const std::vector<Eigen::Vector3d>& points, const Eigen::Vector3d& viewpoint,
                          const FittedPlaneOptions& options = {});

// The regular start grid (MakeStartGrid, spacing in metres) laid into the plane.
TinMesh MakeFittedPlaneMesh(const FittedPlane& plane, double spacing);

// The same grid with each node moved along the plane's normal to the tie points' relief
// there: StartFromTiePoints in the plane's frame (u, v, distance along the normal), so a
// fountain's basin standing 1.5 m in front of its wall starts in front of it, not on the
// wall. Throws std::runtime_error when fewer than options.min_points_total points lie over
// the plane's extent.
TinMesh MakeFittedTiePointMesh(const FittedPlane& plane, const std::vector<Eigen::Vector3d>& points,
                               double spacing, const TiePointStartOptions& options,
                               TiePointStartReport* report = nullptr);

}  // namespace facets
