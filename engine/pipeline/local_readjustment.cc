#include "engine/pipeline/local_readjustment.h"

#include <cmath>
#include <stdexcept>
#include <utility>
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

  // The windows' fit before the search and after their adjustment, each by one
  // linearisation of a copy with the same windows: the first linearisation's sigma0
  // differs from a converged one (on a level with robust weights, the V-cycle's, by 15-20 %
  // on the rendered block), so the round is judged by two measures of the same kind.
  AdjustmentOptions probe_adjustment = adjustment;
  probe_adjustment.max_iterations = 1;
  probe_adjustment.compute_precision = false;
  probe_adjustment.residual_correlation = false;
  LevelWindowOptions probe_options = options;
  probe_options.sweeps = 1;
  probe_options.crease_second_pass = false;
  auto probe = [&](const TinMesh& surface) {
    TinMesh copy = surface;
    return AdjustLevelInWindows(&copy, images, probe_adjustment, probe_options, false, nullptr, &scope).summary;
  };
  const WindowReport was = probe(before);
  // One sweep: the local windows start from the adjusted level with their margins held at
  // its values (LocalScope), so a second sweep moves little but the seams between them;
  // on the rendered blocks at level 1 it cost 34-41 % of the run's CPU time for walls
  // within 2.5 points (docs/BENCHMARKS.md).
  LevelWindowOptions local_options = options;
  local_options.sweeps = 1;
  result.level = AdjustLevelInWindows(mesh, images, adjustment, local_options, keep_grey, progress, &scope);
  const WindowReport after = probe(*mesh);
  result.sigma0_before = was.sigma0;
  result.sigma0_after = after.sigma0;

  // The level's summary: the local windows' share replaced, their converged sigma0 before
  // taken as the one after scaled by the probes' ratio.
  const WindowReport& full = adjusted.summary;
  WindowReport& now = result.level.summary;
  const double ratio = after.sigma0 > 0.0 ? was.sigma0 / after.sigma0 : 1.0;
  const double share_before = now.sigma0 * ratio * now.sigma0 * ratio * static_cast<double>(was.redundancy);
  const double redundancy = static_cast<double>(full.redundancy - was.redundancy + now.redundancy);
  const double pooled = full.sigma0 * full.sigma0 * static_cast<double>(full.redundancy) - share_before +
                        now.sigma0 * now.sigma0 * static_cast<double>(now.redundancy);
  WindowReport merged = full;
  merged.sigma0 = redundancy > 0 && pooled > 0 ? std::sqrt(pooled / redundancy) : now.sigma0;
  merged.redundancy = static_cast<long long>(redundancy);
  merged.observations = full.observations - was.observations + now.observations;
  merged.vertex_sigma = std::move(now.vertex_sigma);
  merged.vertex_views = std::move(now.vertex_views);
  merged.vertex_flags = std::move(now.vertex_flags);
  result.level.summary = std::move(merged);
  result.level.windows = adjusted.windows;
  result.level.window_core_faces = adjusted.window_core_faces;
  result.level.groups = adjusted.groups;
  return result;
}

}  // namespace facets
