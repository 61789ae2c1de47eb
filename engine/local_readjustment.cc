#include "engine/local_readjustment.h"

#include <cmath>
#include <stdexcept>
#include <vector>

#include "mesh/windows.h"

namespace facets {

LocalReadjustment ReadjustAroundMovedVertices(TinMesh* mesh, const TinMesh& before,
                                              const LevelAdjustment& adjusted, int rings,
                                              const WindowImages& images,
                                              const AdjustmentOptions& adjustment,
                                              const LevelWindowOptions& options, bool keep_grey,
                                              const std::function<void(const std::string&)>& progress) {
  if (before.n_vertices() != mesh->n_vertices() || before.n_faces() != mesh->n_faces()) {
    throw std::invalid_argument("local re-adjustment: the surface before must have the same topology");
  }
  LocalReadjustment result;
  std::vector<char> moved(mesh->n_vertices(), 0);
  for (auto vh : mesh->vertices()) moved[vh.idx()] = mesh->point(vh) != before.point(vh);
  LocalScope scope;
  scope.previous = &adjusted;
  scope.windows = PartitionFacesIntoWindows(*mesh, FacesNearVertices(*mesh, moved, rings), options.partition);
  if (scope.windows.empty()) return result;
  result.windows = static_cast<int>(scope.windows.size());

  // The same windows on the surface before the search: one linearisation gives their
  // sigma0 there (the level's sigma0 pools every window, most of them unmoved).
  TinMesh probe = before;
  AdjustmentOptions probe_adjustment = adjustment;
  probe_adjustment.max_iterations = 1;
  probe_adjustment.compute_precision = false;
  LevelWindowOptions probe_options = options;
  probe_options.sweeps = 1;
  probe_options.crease_second_pass = false;
  const LevelAdjustment was = AdjustLevelInWindows(&probe, images, probe_adjustment, probe_options, false, nullptr, &scope);
  result.level = AdjustLevelInWindows(mesh, images, adjustment, options, keep_grey, progress, &scope);
  result.sigma0_before = was.summary.sigma0;
  result.sigma0_after = result.level.summary.sigma0;

  const WindowReport& full = adjusted.summary;
  const WindowReport& now = result.level.summary;
  const double redundancy = static_cast<double>(full.redundancy - was.summary.redundancy + now.redundancy);
  const double pooled = full.sigma0 * full.sigma0 * full.redundancy -
                        was.summary.sigma0 * was.summary.sigma0 * was.summary.redundancy +
                        now.sigma0 * now.sigma0 * now.redundancy;
  WindowReport merged = full;
  merged.sigma0 = redundancy > 0 && pooled > 0 ? std::sqrt(pooled / redundancy) : now.sigma0;
  merged.redundancy = static_cast<long long>(redundancy);
  merged.observations = full.observations - was.summary.observations + now.observations;
  merged.vertex_sigma = now.vertex_sigma;
  merged.vertex_views = now.vertex_views;
  merged.vertex_flags = now.vertex_flags;
  result.level.summary = std::move(merged);
  result.level.windows = adjusted.windows;
  result.level.window_core_faces = adjusted.window_core_faces;
  result.level.groups = adjusted.groups;
  return result;
}

}  // namespace facets
