// Start surface fitted robustly to the tie points (DESIGN.md section 5): the
// coarsest level's start TIN with heights from the block's sparse points (COLMAP
// points3D.txt, ImageBlock::points) instead of one plane.
//
// Tie points carry gross errors (mismatches, points on cars and trees) and scatter
// unevenly, so every step is robust:
//   1. a robust plane over all points in the region: least squares, then points
//      beyond k x 1.4826 x MAD of the residuals dropped and the plane fitted again;
//   2. per grid node the points within a neighbourhood (grown until it holds
//      min_points, up to max_radius_nodes spacings): the local plane that at least
//      min_inliers points agree with (within consensus_tolerance; planes through
//      triples of the points, none steeper than 45 degrees), those nearest the node
//      weighing most, refitted to them; the node takes its height. On a building edge
//      it takes one side (the one under the node), not a wall in between;
//   3. nodes without enough points take the robust plane (holes, the region's border);
//   4. a few passes of smoothing (each node's deviation from the robust plane halfway
//      to its 4 neighbours' mean), so one wrong node does not start a spike.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "io/image_block.h"
#include "mesh/tin.h"

namespace facets {

struct TiePointStartOptions {
  // Fewest tie points inside the region for the fitted start (else the plane).
  int min_points_total = 20;
  // Points a node needs in its neighbourhood to get its own height.
  int min_points = 5;
  // The neighbourhood starts at this radius (in node spacings) and doubles up to
  // max_radius_nodes while it holds fewer than min_points.
  double radius_nodes = 1.0;
  double max_radius_nodes = 4.0;
  // Robust plane (step 1), outliers: |residual - median| > max(mad_factor x 1.4826 x
  // MAD, min_tolerance).
  double mad_factor = 3.0;
  double min_tolerance = 0.3;  // m
  // A point agrees with a local plane within this distance (m): tie-point noise
  // (centimetres) plus the curvature of the terrain over a neighbourhood.
  double consensus_tolerance = 0.5;
  int smoothing_passes = 1;
  // The local plane needs this many agreeing points; among planes that have them, the
  // one whose agreeing points lie closest to the node wins (weights
  // exp(-d^2 / (weight_radius_nodes x spacing)^2)).
  int min_inliers = 4;
  double weight_radius_nodes = 1.0;

  void Check() const;  // throws std::invalid_argument naming the option
};

// What the fit did (for the report and the log).
struct TiePointStartReport {
  int points_in_region = 0;
  int points_rejected_by_plane = 0;  // beyond the plane's MAD bound (step 1)
  int nodes = 0;
  int nodes_from_points = 0;  // step 2
  int nodes_from_plane = 0;   // step 3 (holes)
  Eigen::Vector3d plane = Eigen::Vector3d::Zero();  // z = a + b x + c y
  std::string Brief() const;
};

// Heights on the grid MakeStartGrid builds for (min, max, spacing): (nx + 1) x (ny + 1)
// nodes, row-major from min, fitted to the points over the region's XY rectangle at any
// height (the robust plane and the local consensus drop blunders). Throws
// std::runtime_error when fewer than options.min_points_total points lie over it.
struct TiePointHeightGrid {
  Eigen::Vector2d min = Eigen::Vector2d::Zero(), max = Eigen::Vector2d::Zero();
  int nx = 0, ny = 0;
  std::vector<double> heights;
  double At(double x, double y) const;  // the nearest node's height
};
TiePointHeightGrid FitTiePointHeights(const std::vector<Eigen::Vector3d>& points,
                                      const RegionOfInterest& roi, double spacing,
                                      const TiePointStartOptions& options = {},
                                      TiePointStartReport* report = nullptr);

// The start TIN over the region with the fitted heights.
TinMesh StartFromTiePoints(const std::vector<Eigen::Vector3d>& points, const RegionOfInterest& roi,
                           double spacing, const TiePointStartOptions& options = {},
                           TiePointStartReport* report = nullptr);

// Which start surface the reconstruction builds on the coarsest level.
enum class StartSurfaceKind {
  kAuto,       // tie points when enough lie in the region and no plane height is asked for
  kPlane,      // a plane at the start height
  kTiePoints,  // the fitted tie-point surface (an error when too few points)
};
// "auto" | "plane" | "tiepoints"; throws std::invalid_argument naming the value.
StartSurfaceKind StartSurfaceFromName(const std::string& name);
// kAuto resolved: tie points when at least options.min_points_total lie in the region
// and the plane is not wanted explicitly (a given start height or object lifting).
bool UseTiePointStart(StartSurfaceKind kind, int points_in_region, bool plane_height_chosen,
                      const TiePointStartOptions& options);

// Tie points of the block inside the region's XY rectangle and Z range.
std::vector<Eigen::Vector3d> TiePointsInRegion(const ImageBlock& block, const RegionOfInterest& roi);
// Whether p lies over the region's XY rectangle, at any height.
bool OverFootprint(const RegionOfInterest& roi, const Eigen::Vector3d& p);
// Tie points of the block over the region's XY rectangle, at any height: an aerial start
// needs the points of the tallest roofs, which a region derived from the tie points'
// height percentiles (engine/pipeline/region_choice.h) leaves above its Z range.
std::vector<Eigen::Vector3d> TiePointsOverFootprint(const ImageBlock& block, const RegionOfInterest& roi);

}  // namespace facets
