#include "engine/pipeline/straighten_stage.h"

#include <utility>

#include "engine/pipeline/trial.h"
#include "mesh/creases.h"

namespace facets {
namespace {

// Why nothing moved, so that a run's log tells.
std::string NothingMovedLine(const LevelPass& pass, const StraightenReport& straight) {
  return pass.Prefix() + " straightening: " + std::to_string(straight.sets) + " crease sets, " +
         std::to_string(straight.lines) + " straight runs, none moved (" + std::to_string(straight.sides_not_planar) +
         " with a side not planar, " + std::to_string(straight.sides_not_meeting) +
         " with sides not meeting on the run, " + std::to_string(straight.too_small + straight.too_short) +
         " too short, " + std::to_string(straight.rejected) + " undone for folds)";
}

std::string RoundLine(const LevelPass& pass, int round, const StraightenReport& straight,
                      const TrialVerdict& verdict) {
  return pass.Prefix() + " straightening " + std::to_string(round + 1) + ": " + std::to_string(straight.components) +
         " straight crease lines, " + std::to_string(straight.moved) + " vertices put on them (max " +
         std::to_string(straight.max_move) + " m, " + std::to_string(straight.left_off) + " left off for folds, " +
         std::to_string(straight.flipped) + " faces of no area flipped); " + verdict.Brief() +
         (verdict.kept ? ", kept" : ", dropped");
}

}  // namespace

void StraightenCreases(const RunContext& run, LevelPass* pass) {
  const ReconstructionOptions& options = run.options;
  if (run.closed) return;
  TinMesh& mesh = *pass->mesh;
  for (int round = 0; round < options.straighten_rounds; ++round) {
    TinMesh before = mesh;
    const StraightenReport straight = StraightenCreaseChains(
        &mesh, DetectCreaseEdges(mesh, pass->adjustment.crease_angle_deg, pass->adjustment.rounded_ridges));
    if (straight.moved == 0) {
      if (straight.sets > 0) run.Say(NothingMovedLine(*pass, straight));
      break;
    }
    const TrialVerdict verdict =
        JudgeProposal(run, pass, std::move(before), options.straighten_local_rings, options.straighten_tolerance);
    if (!verdict.ran) break;
    run.Say(RoundLine(*pass, round, straight, verdict));
    if (!verdict.kept) {
      ++pass->report.straighten_dropped;
      break;
    }
    ++pass->report.straighten_kept;
    pass->report.straightened += straight.moved;
  }
}

}  // namespace facets
