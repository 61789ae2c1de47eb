#include "engine/pipeline/v_cycle.h"

#include <vector>

#include "mesh/surface_validity.h"
#include "visibility/embree_scene.h"

namespace facets {

ProjectionReport ProjectAlongNormals(TinMesh* mesh, const Tessellation& surface, double max_distance) {
  ProjectionReport report;
  if (surface.triangles.empty()) return report;
  const TriangleScene scene(EmbreeDevice::Shared(), surface.points, surface.triangles);
  std::vector<Eigen::Vector3d> before;
  for (auto vh : mesh->vertices()) before.push_back(ToEigen(mesh->point(vh)));
  const float reach = static_cast<float>(max_distance);
  for (auto vh : mesh->vertices()) {
    const Eigen::Vector3d p = before[vh.idx()];
    const Eigen::Vector3d normal = ToEigen(mesh->normal(vh)).normalized();
    const RayHit out = scene.Intersect(p, normal, 0.0f, reach);
    const RayHit in = scene.Intersect(p, -normal, 0.0f, reach);
    if (!out.hit && !in.hit) {
      ++report.missed;
      continue;
    }
    const double offset = !in.hit || (out.hit && out.distance <= in.distance) ? out.distance : -in.distance;
    mesh->set_point(vh, ToOpenMesh(p + offset * normal));
  }
  CopyStepFields(GuardAndMeasureStep(mesh, before, 1e-9), &report);
  return report;
}

}  // namespace facets
