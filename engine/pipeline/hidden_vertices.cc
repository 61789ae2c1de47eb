#include "engine/pipeline/hidden_vertices.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "mesh/closed_surface.h"
#include "visibility/embree_scene.h"

namespace facets {

std::vector<int> VisibleViews(const TinMesh& mesh, const ImageBlock& block, double tolerance) {
  std::vector<Eigen::Vector3d> points;
  std::vector<Eigen::Vector3i> triangles;
  TinPointsAndTriangles(mesh, &points, &triangles);
  std::vector<int> views(points.size(), 0);
  if (triangles.empty()) return views;
  const TriangleScene scene(EmbreeDevice::Shared(), points, triangles);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, points.size()), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t v = r.begin(); v != r.end(); ++v) {
      const Eigen::Vector3d& p = points[v];
      const Eigen::Vector3d normal = ToEigen(mesh.normal(mesh.vertex_handle(static_cast<int>(v))));
      for (const BlockImage& image : block.images) {
        const Eigen::Vector3d centre = image.ProjectionCentre();
        const Eigen::Vector3d d = p - centre;
        const double length = d.norm();
        if (!(length > tolerance) || normal.dot(-d) <= 0.0) continue;
        const Eigen::Vector3d in_cam = image.cam_from_world * p;
        if (!(in_cam.z() > 0)) continue;
        const Camera& camera = block.CameraOf(image);
        const double x = camera.FocalX() * in_cam.x() / in_cam.z() + camera.PrincipalX();
        const double y = camera.FocalY() * in_cam.y() / in_cam.z() + camera.PrincipalY();
        if (x < 0 || x > camera.width || y < 0 || y > camera.height) continue;
        const RayHit hit = scene.Intersect(centre, d, 0.0f, static_cast<float>(1.0 - tolerance / length));
        if (!hit.hit) ++views[v];
      }
    }
  });
  return views;
}

}  // namespace facets
