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

// The faces of the windows' cores.
std::vector<int> CoreFaces(const LocalScope& scope) {
  std::vector<int> faces;
  for (const MeshWindow& w : scope.windows) faces.insert(faces.end(), w.core_faces.begin(), w.core_faces.end());
  return faces;
}

// The windows' fit on `surface` from one linearisation of a copy with the same windows:
// the first linearisation's sigma0 differs from a converged one (on a level with robust
// weights, the V-cycle's, by 15-20 % on the rendered block), so a judged trial is judged by
// two measures of the same kind.
WindowReport Probe(const TinMesh& surface, const LocalScope& scope, const WindowImages& images,
                   const AdjustmentOptions& adjustment, const LevelWindowOptions& options) {
  AdjustmentOptions probe_adjustment = adjustment;
  probe_adjustment.max_iterations = 1;
  probe_adjustment.compute_precision = false;
  probe_adjustment.residual_correlation = false;
  LevelWindowOptions probe_options = options;
  probe_options.sweeps = 1;
  probe_options.crease_second_pass = false;
  TinMesh copy = surface;
  return AdjustLevelInWindows(&copy, images, probe_adjustment, probe_options, false, nullptr, &scope).summary;
}

// `mesh` adjusted in the windows of `scope` (`before`: the surface `adjusted` left, of
// the same topology when probed).
LocalReadjustment ReadjustInScope(TinMesh* mesh, const TinMesh& before, const LevelAdjustment& adjusted,
                                  const LocalScope& scope, const WindowImages& images,
                                  const AdjustmentOptions& adjustment, const LevelWindowOptions& options,
                                  bool keep_grey, bool probed,
                                  const std::function<void(const std::string&)>& progress) {
  LocalReadjustment result;
  result.windows = static_cast<int>(scope.windows.size());
  result.probed = probed;
  WindowReport was;
  if (probed) was = Probe(before, scope, images, adjustment, options);
  // One sweep: the local windows start from the adjusted level with their margins held at
  // its values (LocalScope), so a second sweep moves little but the seams between them;
  // on the rendered blocks at level 1 it cost 34-41 % of the run's CPU time for walls
  // within 2.5 points (docs/BENCHMARKS.md).
  LevelWindowOptions local_options = options;
  local_options.sweeps = 1;
  result.level = AdjustLevelInWindows(mesh, images, adjustment, local_options, keep_grey, progress, &scope);
  if (probed) {
    result.sigma0_before = was.sigma0;
    result.sigma0_after = Probe(*mesh, scope, images, adjustment, options).sigma0;
  } else {
    const std::vector<int> cores = CoreFaces(scope);
    result.sigma0_before = adjusted.face_fit.Sigma0(&cores);
    result.sigma0_after = result.level.face_fit.Sigma0(&cores);
  }

  // The level's summary: sigma0, redundancy and observations of the whole level from the
  // faces' parts, the local windows' in place of those before.
  WindowReport merged = adjusted.summary;
  WindowReport& now = result.level.summary;
  const FaceFit& fit = result.level.face_fit;
  merged.sigma0 = fit.Sigma0();
  merged.redundancy = std::llround(fit.TotalRedundancy());
  merged.observations = std::llround(fit.TotalObservations());
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
                                              const LevelWindowOptions& options, bool keep_grey, bool probed,
                                              const std::function<void(const std::string&)>& progress) {
  if (before.n_vertices() != mesh->n_vertices() || before.n_faces() != mesh->n_faces()) {
    throw std::invalid_argument("local re-adjustment: the surface before must have the same topology");
  }
  std::vector<bool> moved(mesh->n_vertices(), false);
  for (auto vh : mesh->vertices()) moved[vh.idx()] = mesh->point(vh) != before.point(vh);
  const LocalScope scope = ScopeAround(*mesh, moved, rings, &adjusted, options);
  if (scope.windows.empty()) return {};
  return ReadjustInScope(mesh, before, adjusted, scope, images, adjustment, options, keep_grey, probed, progress);
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
  return ReadjustInScope(mesh, before, extended, scope, images, adjustment, options, keep_grey, false, progress);
}

}  // namespace facets
