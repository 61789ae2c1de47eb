// Geometric checks of a reconstruction beside the sample distances: the lean of the
// truth's leaning walls as reconstructed, height errors on a grid, plane fits.
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "mesh/principal_axes.h"
#include "scenes/evaluate.h"
#include "visibility/embree_scene.h"

namespace facets {

std::vector<WallLean> EvaluateLeaningWalls(const TruthScene& truth, const MeshData& reconstruction,
                                           const std::optional<RegionOfInterest>& roi, double band) {
  std::vector<WallLean> result;
  const double deg = M_PI / 180.0;
  const Eigen::Vector2d sides[4] = {{1, 0}, {0, 1}, {-1, 0}, {0, -1}};
  const auto& tv = truth.mesh.vertices;
  for (size_t bi = 0; bi < truth.buildings.size(); ++bi) {
    const TruthBuilding& b = truth.buildings[bi];
    const double ca = std::cos(b.azimuth_deg * deg), sa = std::sin(b.azimuth_deg * deg);
    for (int w = 0; w < 4; ++w) {
      if (b.wall_lean_deg[w] == 0.0) continue;
      const Eigen::Vector3d out(ca * sides[w].x() - sa * sides[w].y(), sa * sides[w].x() + ca * sides[w].y(), 0);
      const double lean = b.wall_lean_deg[w] * deg;
      // Outward lean: the top moves out, so the outward normal looks down.
      const Eigen::Vector3d expected = std::cos(lean) * out - std::sin(lean) * Eigen::Vector3d::UnitZ();
      const double reach = 0.75 * std::hypot(b.length, b.width) + b.height;
      std::vector<Eigen::Vector3d> wall_points;
      for (size_t f = 0; f < truth.mesh.faces.size(); ++f) {
        if (truth.mesh.face_labels.empty() || truth.mesh.face_labels[f] != 2) continue;  // walls only
        const auto& t = truth.mesh.faces[f];
        const Eigen::Vector3d n = (tv[t[1]] - tv[t[0]]).cross(tv[t[2]] - tv[t[0]]).normalized();
        const Eigen::Vector3d centroid = (tv[t[0]] + tv[t[1]] + tv[t[2]]) / 3.0;
        if (n.dot(expected) < std::cos(2 * deg) || (centroid - b.centre).head<2>().norm() > reach) continue;
        for (int k = 0; k < 3; ++k) wall_points.push_back(tv[t[k]]);
      }
      if (wall_points.size() < 3) continue;
      WallLean lean_row;
      lean_row.building = static_cast<int>(bi);
      lean_row.wall = w;
      lean_row.true_lean_deg = b.wall_lean_deg[w];
      auto signed_lean = [&](const PlaneFit& fit) {
        const Eigen::Vector3d n = fit.normal.dot(out) < 0 ? Eigen::Vector3d(-fit.normal) : fit.normal;
        return std::asin(std::clamp(-n.z(), -1.0, 1.0)) / deg;
      };
      const PlaneFit truth_fit = FitPlane(wall_points);
      lean_row.truth_fit_lean_deg = signed_lean(truth_fit);
      const Eigen::Vector3d along = Eigen::Vector3d::UnitZ().cross(out);
      double s_min = 1e300, s_max = -1e300, eave = -1e300;
      for (const auto& p : wall_points) {
        s_min = std::min(s_min, p.dot(along));
        s_max = std::max(s_max, p.dot(along));
        eave = std::max(eave, p.z());
      }
      const double foot = eave - b.height;
      std::vector<Eigen::Vector3d> near;
      for (const auto& p : reconstruction.vertices) {
        if (roi && !roi->Contains(p)) continue;
        const double s = p.dot(along);
        if (s < s_min + 1.0 || s > s_max - 1.0) continue;
        if (p.z() < foot + 0.15 * b.height || p.z() > eave - 0.15 * b.height) continue;
        if (std::abs((p - truth_fit.centroid).dot(truth_fit.normal)) > band) continue;
        near.push_back(p);
      }
      lean_row.lean_deg = std::numeric_limits<double>::quiet_NaN();
      if (near.size() >= 10) {
        try {
          PlaneFit fit = FitPlane(near);
          // One robust round: points beyond 2.5 rms (a roof or ground patch in the band)
          // are left out and the plane fitted again.
          std::vector<Eigen::Vector3d> kept;
          for (const auto& p : near) {
            if (std::abs((p - fit.centroid).dot(fit.normal)) <= 2.5 * fit.rms) kept.push_back(p);
          }
          if (kept.size() >= 10) fit = FitPlane(kept);
          lean_row.lean_deg = signed_lean(fit);
          lean_row.vertices = static_cast<int>(kept.size() >= 10 ? kept.size() : near.size());
          lean_row.rms = fit.rms;
        } catch (const std::invalid_argument&) {
          // Collinear vertices: no plane, lean stays NaN.
        }
      }
      if (roi && near.empty() && !roi->Contains(truth_fit.centroid)) continue;  // wall outside the region
      result.push_back(lean_row);
    }
  }
  return result;
}

HeightErrors EvaluateHeights(const MeshData& truth, const MeshData& reconstruction,
                             const RegionOfInterest& roi, double spacing, double border) {
  HeightErrors h;
  h.spacing = spacing;
  const TriangleScene truth_scene(EmbreeDevice::Shared(), truth.vertices, truth.faces);
  const TriangleScene rec_scene(EmbreeDevice::Shared(), reconstruction.vertices, reconstruction.faces);
  // Rays start above everything: the highest point wins, as in a DSM.
  double top = roi.max.z();
  for (const auto& v : truth.vertices) top = std::max(top, v.z());
  for (const auto& v : reconstruction.vertices) top = std::max(top, v.z());
  top += 10.0;
  const Eigen::Vector3d down(0, 0, -1);
  double sum = 0, sum2 = 0;
  h.min = 1e300;
  h.max = -1e300;
  for (double y = roi.min.y() + border; y <= roi.max.y() - border + 1e-9; y += spacing) {
    for (double x = roi.min.x() + border; x <= roi.max.x() - border + 1e-9; x += spacing) {
      const Eigen::Vector3d origin(x, y, top);
      const RayHit t = truth_scene.Intersect(origin, down);
      if (!t.hit) continue;
      const RayHit r = rec_scene.Intersect(origin, down);
      if (!r.hit) {
        ++h.missing;
        continue;
      }
      // Embree's float distances are exact enough for centimetres at tens of metres.
      const double dz = static_cast<double>(t.distance) - static_cast<double>(r.distance);
      sum += dz;
      sum2 += dz * dz;
      h.min = std::min(h.min, dz);
      h.max = std::max(h.max, dz);
      ++h.count;
    }
  }
  if (h.count > 0) {
    h.mean = sum / h.count;
    h.rms = std::sqrt(sum2 / h.count);
  } else {
    h.min = h.max = 0;
  }
  return h;
}

PlaneFit FitPlane(const std::vector<Eigen::Vector3d>& points) {
  if (points.size() < 3) throw std::invalid_argument("FitPlane: fewer than 3 points");
  PlaneFit fit;
  const PrincipalAxes principal = FitPrincipalAxes(points);
  fit.centroid = principal.centre;
  const Eigen::Vector3d ev = principal.eigenvalues;  // ascending
  if (!(ev(1) > 1e-12 * std::max(ev(2), 1e-300))) {
    throw std::invalid_argument("FitPlane: points are collinear or coincide");
  }
  fit.normal = principal.Normal().normalized();
  if (fit.normal.z() < 0) fit.normal = -fit.normal;
  double sum2 = 0;
  for (const auto& p : points) {
    const double r = (p - fit.centroid).dot(fit.normal);
    sum2 += r * r;
    fit.max_abs_residual = std::max(fit.max_abs_residual, std::abs(r));
  }
  fit.rms = std::sqrt(sum2 / static_cast<double>(points.size()));
  fit.tilt_from_vertical_deg = std::asin(std::min(1.0, std::abs(fit.normal.z()))) * 180.0 / M_PI;
  fit.slope_deg = 90.0 - fit.tilt_from_vertical_deg;
  return fit;
}

}  // namespace facets
