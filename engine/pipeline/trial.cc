#include "engine/pipeline/trial.h"

#include <utility>

#include "engine/pipeline/local_readjustment.h"
#include "mesh/local_ops.h"
#include "mesh/surface_validity.h"

namespace facets {

std::string TrialVerdict::Brief() const {
  std::string where = local_windows > 0 ? std::to_string(local_windows) + " local windows" : std::string();
  if (!judged) where += std::string(where.empty() ? "" : ", ") + "not judged";
  return "sigma0 " + std::to_string(now_sigma0) + " against " + std::to_string(was_sigma0) +
         (where.empty() ? "" : " (" + where + ")");
}

TrialVerdict JudgeProposal(const RunContext& run, LevelPass* pass, TinMesh before, int local_rings,
                           double tolerance) {
  const auto clock = run.profile->Part("trial re-adjustment");
  TrialVerdict verdict;
  verdict.judged = tolerance < kKeptWhateverSigma0;
  verdict.was_sigma0 = pass->adjusted.summary.sigma0;
  const bool keep_grey = pass->Finest(run);
  LevelAdjustment again;
  if (local_rings >= 0) {
    LocalReadjustment local =
        ReadjustAroundMovedVertices(pass->mesh, before, pass->adjusted, local_rings, run.images.ForWindows(pass->level),
                                    pass->adjustment, run.options.windows, keep_grey, verdict.judged,
                                    run.options.progress);
    verdict.ran = local.windows > 0;
    again = std::move(local.level);
    verdict.was_sigma0 = local.sigma0_before;
    verdict.now_sigma0 = local.sigma0_after;
    verdict.local_windows = local.windows;
  } else {
    again = AdjustLevelInWindows(pass->mesh, run.images.ForWindows(pass->level), pass->adjustment,
                                 run.options.windows, keep_grey, run.options.progress);
    verdict.now_sigma0 = again.summary.sigma0;
  }
  verdict.kept = verdict.ran && (!verdict.judged || verdict.now_sigma0 < verdict.was_sigma0 * (1.0 + tolerance));
  if (verdict.kept) {
    pass->adjusted = std::move(again);
  } else {
    *pass->mesh = std::move(before);
  }
  return verdict;
}

SurfaceFaults CountSurfaceFaults(const RunContext& run, const TinMesh& mesh) {
  const auto clock = run.profile->Part("crossing counts");
  return {CountSelfIntersections(mesh), CountFoldedFaces(mesh)};
}

std::vector<bool> TrialNeighbourhood(const TinMesh& mesh, const TinMesh& before) {
  return GrowByRings(mesh, VerticesChangedFrom(mesh, before), kTrialUntangleRings);
}

SurfaceFaults UntangleNewFaults(const RunContext& run, TinMesh* mesh, const TinMesh& before_mesh,
                                const SurfaceFaults& before, int rounds) {
  SurfaceFaults now = CountSurfaceFaults(run, *mesh);
  if (!now.WorseThan(before) || rounds <= 0) return now;
  const auto clock = run.profile->Part("untangling");
  const std::vector<bool> movable = TrialNeighbourhood(*mesh, before_mesh);
  now.crossing = UntangleSelfIntersections(mesh, rounds, &movable).pairs_after;
  UpdateVertexNormals(mesh);
  now.folded = CountFoldedFaces(*mesh);
  return now;
}

}  // namespace facets
