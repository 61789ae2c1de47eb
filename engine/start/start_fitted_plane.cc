#include "engine/start/start_fitted_plane.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "mesh/principal_axes.h"

namespace facets {
namespace {

struct PlaneFit {
  Eigen::Vector3d centre;
  Eigen::Matrix3d axes;  // columns: largest, middle, smallest eigenvector
  Eigen::Vector3d eigenvalues;  // ascending
};

PlaneFit FitTls(const std::vector<Eigen::Vector3d>& points) {
  const PrincipalAxes principal = FitPrincipalAxes(points);
  PlaneFit fit;
  fit.centre = principal.centre;
  fit.eigenvalues = principal.eigenvalues;
  for (int i = 0; i < 3; ++i) fit.axes.col(i) = principal.axes.col(2 - i);
  return fit;
}

double Quantile(std::vector<double> v, double q) {
  std::sort(v.begin(), v.end());
  return v[static_cast<size_t>(std::clamp(q, 0.0, 1.0) * (v.size() - 1))];
}

}  // namespace

FittedPlane FitStartPlane(const std::vector<Eigen::Vector3d>& points, const Eigen::Vector3d& viewpoint,
                          const FittedPlaneOptions& options) {
  if (static_cast<int>(points.size()) < std::max(3, options.min_points)) {
    throw std::runtime_error("fitted start plane: " + std::to_string(points.size()) +
                             " tie points in the region, need at least " +
                             std::to_string(std::max(3, options.min_points)));
  }
  std::vector<Eigen::Vector3d> kept = points;
  PlaneFit fit = FitTls(kept);
  for (int round = 0; round < options.rounds; ++round) {
    const Eigen::Vector3d n = fit.axes.col(2);
    std::vector<double> distance;
    distance.reserve(kept.size());
    for (const auto& p : kept) distance.push_back(std::abs(n.dot(p - fit.centre)));
    // Distances are >= 0 with a median near 0 for inliers: the MAD about zero is the median.
    const double sigma = 1.4826 * Quantile(distance, 0.5);
    if (!(sigma > 0.0)) break;
    std::vector<Eigen::Vector3d> next;
    for (size_t i = 0; i < kept.size(); ++i) {
      if (distance[i] <= options.rejection_k * sigma) next.push_back(kept[i]);
    }
    if (next.size() == kept.size() || static_cast<int>(next.size()) < std::max(3, options.min_points)) break;
    kept = std::move(next);
    fit = FitTls(kept);
  }
  // Two in-plane directions must carry the spread, or the "plane" is a line.
  if (!(fit.eigenvalues[1] > 1e-12 * std::max(1.0, fit.eigenvalues[2]))) {
    throw std::runtime_error("fitted start plane: the tie points are (nearly) collinear");
  }
  FittedPlane plane;
  plane.centre = fit.centre;
  plane.normal = fit.axes.col(2).normalized();
  if (plane.normal.dot(viewpoint - plane.centre) < 0.0) plane.normal = -plane.normal;
  plane.axis_u = fit.axes.col(0).normalized();
  plane.axis_v = plane.normal.cross(plane.axis_u).normalized();
  std::vector<double> u, v;
  double sum2 = 0.0;
  for (const auto& p : kept) {
    u.push_back(plane.axis_u.dot(p - plane.centre));
    v.push_back(plane.axis_v.dot(p - plane.centre));
    sum2 += std::pow(plane.normal.dot(p - plane.centre), 2);
  }
  plane.min_uv = {Quantile(u, options.extent_quantile), Quantile(v, options.extent_quantile)};
  plane.max_uv = {Quantile(u, 1.0 - options.extent_quantile), Quantile(v, 1.0 - options.extent_quantile)};
  plane.rms = std::sqrt(sum2 / kept.size());
  plane.kept = static_cast<int>(kept.size());
  plane.total = static_cast<int>(points.size());
  plane.tilt_deg = std::acos(std::clamp(std::abs(plane.normal.z()), 0.0, 1.0)) * 180.0 / M_PI;
  return plane;
}

namespace {

// Grid (u, v, w) -> centre + u axis_u + v axis_v + w normal; a proper rotation (axis_u x
// axis_v = normal), so the faces, counter-clockwise seen from +w, face along the normal.
void PlaneFrameToWorld(const FittedPlane& plane, TinMesh* mesh) {
  for (auto vh : mesh->vertices()) {
    const Eigen::Vector3d g = ToEigen(mesh->point(vh));
    mesh->set_point(vh, ToOpenMesh(plane.centre + g.x() * plane.axis_u + g.y() * plane.axis_v + g.z() * plane.normal));
  }
  UpdateVertexNormals(mesh);
}

}  // namespace

TinMesh MakeFittedPlaneMesh(const FittedPlane& plane, double spacing) {
  StartGridOptions grid;
  grid.min = plane.min_uv;
  grid.max = plane.max_uv;
  grid.spacing = spacing;
  grid.plane_height = 0.0;
  TinMesh mesh = MakeStartGrid(grid);
  PlaneFrameToWorld(plane, &mesh);
  return mesh;
}

TinMesh MakeFittedTiePointMesh(const FittedPlane& plane, const std::vector<Eigen::Vector3d>& points,
                               double spacing, const TiePointStartOptions& options, TiePointStartReport* report) {
  std::vector<Eigen::Vector3d> in_frame;
  in_frame.reserve(points.size());
  for (const auto& p : points) {
    const Eigen::Vector3d d = p - plane.centre;
    in_frame.emplace_back(plane.axis_u.dot(d), plane.axis_v.dot(d), plane.normal.dot(d));
  }
  constexpr double kAnyDistance = 1e30;  // the points were chosen by the region already
  RegionOfInterest extent;
  extent.min = Eigen::Vector3d(plane.min_uv.x(), plane.min_uv.y(), -kAnyDistance);
  extent.max = Eigen::Vector3d(plane.max_uv.x(), plane.max_uv.y(), kAnyDistance);
  TinMesh mesh = StartFromTiePoints(in_frame, extent, spacing, options, report);
  PlaneFrameToWorld(plane, &mesh);
  return mesh;
}

}  // namespace facets
