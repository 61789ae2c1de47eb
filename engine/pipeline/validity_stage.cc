#include "engine/pipeline/validity_stage.h"

#include "engine/pipeline/hidden_vertices.h"
#include "mesh/creases.h"
#include "mesh/local_ops.h"
#include "mesh/surface_validity.h"

namespace facets {

void LevelPass::UpdateProductsSurface() {
  const std::vector<bool> creases = DetectCreaseEdges(*mesh, adjustment.crease_angle_deg, adjustment.rounded_ridges);
  UpdateTessellationPoints(BuildPatches(*mesh, ComputeCornerNormals(*mesh, creases)), &adjusted.tessellation);
}

int RelaxUnseen(const RunContext& run, LevelPass* pass) {
  if (!run.options.relax_unseen) return 0;
  const double tolerance = 0.25 * run.EdgeLength(pass->level);  // seen within a quarter of an edge
  const int relaxed = RelaxUnseenVertices(pass->mesh, VisibleViews(*pass->mesh, run.block, tolerance));
  pass->report.relaxed += relaxed;
  UpdateVertexNormals(pass->mesh);
  return relaxed;
}

void HoldInsideVisualHull(const RunContext& run, LevelPass* pass) {
  const ClosedStartOptions& closed = run.options.closed;
  if (!run.closed || !run.closed->visual_hull || !(closed.hull_clamp || closed.hull_rims)) return;
  TinMesh& mesh = *pass->mesh;
  LevelReport& r = pass->report;
  const double edge = run.EdgeLength(pass->level);
  const std::vector<bool> creases =
      DetectCreaseEdges(mesh, pass->adjustment.crease_angle_deg, pass->adjustment.rounded_ridges);
  if (closed.hull_clamp) {
    r.hull_clamped =
        ClampToVisualHull(*run.closed, closed.hull_clamp_edges * edge, &mesh, &r.hull_unresolved, closed.clamp_guard);
  }
  if (closed.hull_rims) {
    r.hull_rim_pushed = PushOntoVisualHullRims(*run.closed, closed.hull_rim_edges * edge, closed.hull_rim_cos, &mesh);
  }
  if (pass->Finest(run) && r.hull_clamped + r.hull_rim_pushed > 0) {
    // Same topology and the creases of the surface before the clamp.
    UpdateTessellationPoints(BuildPatches(mesh, ComputeCornerNormals(mesh, creases)), &pass->adjusted.tessellation);
  }
  run.Say(pass->Prefix() + ": " + std::to_string(r.hull_clamped) + " vertices pulled inside the visual hull, " +
          std::to_string(r.hull_unresolved) + " outside by more than " + std::to_string(closed.hull_clamp_edges) +
          " edges, " + std::to_string(r.hull_rim_pushed) + " pushed out onto its rims");
}

int UntangleCrossings(const RunContext& run, LevelPass* pass) {
  if (!run.options.untangle) return -1;
  UntangleReport untangled;
  {
    const auto clock = run.profile->Part("untangling");
    untangled = UntangleSelfIntersections(pass->mesh);
  }
  if (untangled.rounds == 0) return untangled.pairs_after;
  UpdateVertexNormals(pass->mesh);
  LevelReport& r = pass->report;
  r.crossing_untangled += untangled.pairs_before;
  r.untangle_moved += untangled.vertices_moved;
  r.untangle_membranes += untangled.membranes;
  if (pass->Finest(run)) pass->UpdateProductsSurface();
  run.Say(pass->Prefix() + ": " + std::to_string(untangled.pairs_before) + " crossing triangle pairs untangled in " +
          std::to_string(untangled.rounds) + " rounds (" + std::to_string(untangled.vertices_moved) +
          " vertices moved, " +
          (untangled.membranes > 0 ? std::to_string(untangled.membranes) + " membranes, " : "") +
          std::to_string(untangled.pairs_after) + " pairs left" +
          (untangled.kept_best_round ? ", from the round that left the fewest" : "") + ")");
  return untangled.pairs_after;
}

void CloseLevelReport(const RunContext& run, LevelPass* pass, int crossing_left) {
  const TinMesh& mesh = *pass->mesh;
  LevelReport& r = pass->report;
  r.vertices = static_cast<int>(mesh.n_vertices());
  r.faces = static_cast<int>(mesh.n_faces());
  const auto clock = run.profile->Part("crossing counts");
  r.folded_faces = CountFoldedFaces(mesh);
  r.self_intersections = crossing_left >= 0 ? crossing_left : CountSelfIntersections(mesh);
  for (const WindowReport& w : pass->adjusted.windows) {
    for (const IterationReport& it : w.iterations) r.fold_limited += it.fold_limited;
  }
  run.Say(pass->Prefix() + ": " + std::to_string(r.folded_faces) + " folded faces, " +
          std::to_string(r.self_intersections) + " self-intersecting pairs, " + std::to_string(r.fold_limited) +
          " vertex steps limited by the fold guard, " + std::to_string(r.relaxed) + " unseen vertices relaxed");
  r.window = std::move(pass->adjusted.summary);
  r.windows = std::move(pass->adjusted.windows);
  r.window_core_faces = std::move(pass->adjusted.window_core_faces);
  r.window_groups = pass->adjusted.groups;
}

}  // namespace facets
