#include "engine/pipeline/descent_stage.h"

#include "mesh/creases.h"
#include "mesh/local_ops.h"
#include "mesh/subdivision.h"

namespace facets {

int DescendOneLevel(const RunContext& run, LevelPass* pass) {
  TinMesh& mesh = *pass->mesh;
  const AdjustmentOptions coarser = run.LevelOptions(pass->level + 1, pass->cycle);  // whose creases the mesh has
  mesh = QuaternarySubdivide(mesh, ComputeCornerNormals(mesh, coarser.crease_angle_deg, coarser.rounded_ridges));
  QualityOptions quality;
  quality.target_edge_length = run.EdgeLength(pass->level);
  // Two rounds at most: a diverged level (a surface torn into long spikes) must not
  // multiply the faces.
  quality.max_rounds = 2;
  QualityPass(&mesh, quality);
  UpdateVertexNormals(&mesh);
  if (run.options.tangential_smoothing <= 0) return 0;
  SmoothingOptions smoothing;
  smoothing.iterations = run.options.tangential_smoothing;
  smoothing.crease_angle_deg = coarser.crease_angle_deg;
  smoothing.rounded_ridges = coarser.rounded_ridges;
  smoothing.fix_boundary = true;
  const int smoothed = TangentialSmooth(&mesh, smoothing).moved;
  UpdateVertexNormals(&mesh);
  return smoothed;
}

ProjectionReport GoBackUp(const RunContext& run, LevelPass* pass, const Tessellation& finest_surface) {
  const ProjectionReport projection = ProjectAlongNormals(pass->mesh, finest_surface, run.EdgeLength(pass->level));
  run.Say("stage v-cycle " + std::to_string(pass->cycle) + "/" + std::to_string(run.options.v_cycles) + ": level " +
          std::to_string(pass->level) + "'s TIN onto the level-" + std::to_string(run.finest) + " surface, " +
          std::to_string(projection.moved) + " vertices moved (median " + std::to_string(projection.median_move) +
          " m, max " + std::to_string(projection.max_move) + " m), " + std::to_string(projection.missed) +
          " without a hit, " + std::to_string(projection.limited) + " limited by the fold guard");
  return projection;
}

}  // namespace facets
