#include "engine/pipeline/local_readjustment.h"

#include <cmath>
#include <stdexcept>
#include <utility>
#include <vector>

#include "mesh/local_ops.h"
#include "mesh/windows.h"

namespace facets {

namespace {

// The windows over the faces within `rings` edge rings of the flagged vertices.
LocalScope ScopeAround(const TinMesh& mesh, const std::vector<bool>& flagged, int rings,
                       const LevelAdjustment* previous, const LevelWindowOptions& options) {
  std::vector<char> seeds(mesh.n_vertices(), 0);
  for (size_t v = 0; v < seeds.size() && v < flagged.size(); ++v) seeds[v] = flagged[v] ? 1 : 0;
  LocalScope scope;
  scope.previous = previous;
  scope.windows = PartitionFacesIntoWindows(mesh, FacesNearVertices(mesh, seeds, rings), options.partition);
  return scope;
}

// `after` adjusted in the windows of `scope`, judged against `before` in those of
// `scope_before` (the same windows when the topology is the same).
LocalReadjustment ReadjustInScope(TinMesh* mesh, const TinMesh& before, const LevelAdjustment& adjusted,
                                  const LocalScope& scope, const LocalScope& scope_before, const WindowImages& images,
                                  const AdjustmentOptions& adjustment, const LevelWindowOptions& options,
                                  bool keep_grey, const std::function<void(const std::string&)>& progress) {
  LocalReadjustment result;
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
  auto probe = [&](const TinMesh& surface, const LocalScope& windows) {
    TinMesh copy = surface;
    return AdjustLevelInWindows(&copy, images, probe_adjustment, probe_options, false, nullptr, &windows).summary;
  };
  const WindowReport was = probe(before, scope_before);
  // One sweep: the local windows start from the adjusted level with their margins held at
  // its values (LocalScope), so a second sweep moves little but the seams between them;
  // on the rendered blocks at level 1 it cost 34-41 % of the run's CPU time for walls
  // within 2.5 points (docs/BENCHMARKS.md).
  LevelWindowOptions local_options = options;
  local_options.sweeps = 1;
  result.level = AdjustLevelInWindows(mesh, images, adjustment, local_options, keep_grey, progress, &scope);
  const WindowReport after = probe(*mesh, scope);
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

}  // namespace

LocalReadjustment ReadjustAroundMovedVertices(TinMesh* mesh, const TinMesh& before,
                                              const LevelAdjustment& adjusted, int rings,
                                              const WindowImages& images,
                                              const AdjustmentOptions& adjustment,
                                              const LevelWindowOptions& options, bool keep_grey,
                                              const std::function<void(const std::string&)>& progress) {
  if (before.n_vertices() != mesh->n_vertices() || before.n_faces() != mesh->n_faces()) {
    throw std::invalid_argument("local re-adjustment: the surface before must have the same topology");
  }
  std::vector<bool> moved(mesh->n_vertices(), false);
  for (auto vh : mesh->vertices()) moved[vh.idx()] = mesh->point(vh) != before.point(vh);
  const LocalScope scope = ScopeAround(*mesh, moved, rings, &adjusted, options);
  if (scope.windows.empty()) return {};
  return ReadjustInScope(mesh, before, adjusted, scope, scope, images, adjustment, options, keep_grey, progress);
}

LocalReadjustment ReadjustAroundSplits(TinMesh* mesh, const TinMesh& before, const LevelAdjustment& adjusted,
                                       int rings, const WindowImages& images, const AdjustmentOptions& adjustment,
                                       const LevelWindowOptions& options, bool keep_grey,
                                       const std::function<void(const std::string&)>& progress) {
  const std::vector<bool> changed = VerticesChangedFrom(*mesh, before);
  // The adjustment before, its per-vertex values extended over the inserted vertices
  // (all of them in the local windows' cores, which set their values).
  LevelAdjustment extended = adjusted;
  WindowReport& s = extended.summary;
  s.vertex_sigma.resize(mesh->n_vertices(), 0.0);
  s.vertex_views.resize(mesh->n_vertices(), 0);
  s.vertex_flags.resize(mesh->n_vertices(), kVertexFewViews);
  const LocalScope scope = ScopeAround(*mesh, changed, rings, &extended, options);
  if (scope.windows.empty()) return {};
  const LocalScope scope_before = ScopeAround(before, changed, rings, &adjusted, options);
  return ReadjustInScope(mesh, before, extended, scope, scope_before, images, adjustment, options, keep_grey, progress);
}

}  // namespace facets
