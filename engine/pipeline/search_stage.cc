#include "engine/pipeline/search_stage.h"

#include <utility>

#include "engine/pipeline/trial.h"

namespace facets {
namespace {

std::string PlanesLine(const LevelPass& pass, const PlanePropagationReport& planes) {
  return pass.Prefix() + " plane propagation: " + std::to_string(planes.sources) + " vertices lend their plane, " +
         std::to_string(planes.targets) + " borrow; " + std::to_string(planes.hypotheses) + " planes scored, " +
         std::to_string(planes.moved) + " moved in " + std::to_string(planes.iterations) + " iterations (median " +
         std::to_string(planes.median_move) + " m, max " + std::to_string(planes.max_move) + " m), " +
         std::to_string(planes.limited) + " limited by the fold guard";
}

std::string SearchLine(const LevelPass& pass, const NormalSearchReport& ns) {
  return pass.Prefix() + " normal search: " + std::to_string(ns.searched) + " vertices searched, " +
         std::to_string(ns.peaks) + " peaks, " + std::to_string(ns.moved) + " moved (median " +
         std::to_string(ns.median_move) + " m, max " + std::to_string(ns.max_move) + " m), " +
         std::to_string(ns.limited) + " limited by the fold guard";
}

}  // namespace

bool NormalSearchOn(const RunContext& run) {
  return run.options.normal_search.value_or(!run.closed && !run.fitted);
}

bool LevelSearch::Active() const {
  return NormalSearchOn(run_) && pass_->level != run_.coarsest && pass_->level >= run_.options.normal_search_last_level;
}

NormalSearchReport LevelSearch::Search(PlanePropagationReport* planes) {
  if (images_.empty()) images_ = run_.images.Whole(pass_->level, &storage_);
  const double ground_pixel = run_.GroundPixel(pass_->level);
  NormalSearchReport ns;
  {
    const auto clock = run_.profile->Part("normal search");
    ns = SearchAlongNormals(pass_->mesh, images_, ground_pixel, run_.options.normal_search_options);
  }
  if (run_.options.plane_propagation) {
    const auto clock = run_.profile->Part("plane propagation");
    *planes = PropagatePlanes(pass_->mesh, images_, ground_pixel, run_.options.plane_propagation_options);
    run_.Say(PlanesLine(*pass_, *planes));
    ns.moved += planes->moved;
  }
  return ns;
}

void SearchBeforeLevel(const RunContext& run, LevelPass* pass, LevelSearch* search) {
  if (!search->Active()) return;
  pass->report.normal_search = search->Search(&pass->report.plane_propagation);
  run.Say(SearchLine(*pass, pass->report.normal_search));
}

void SearchRounds(const RunContext& run, LevelPass* pass, LevelSearch* search) {
  const ReconstructionOptions& options = run.options;
  const int rounds_last_level = pass->cycle > 0 && options.v_cycle_rounds_last_level >= 0
                                    ? options.v_cycle_rounds_last_level
                                    : options.normal_search_rounds_last_level;
  if (!search->Active() || pass->level < rounds_last_level) return;
  for (int round = 0; round < options.normal_search_rounds; ++round) {
    TinMesh before = *pass->mesh;
    PlanePropagationReport planes;
    const NormalSearchReport ns = search->Search(&planes);
    if (ns.moved == 0) break;
    const TrialVerdict verdict =
        JudgeProposal(run, pass, std::move(before), options.normal_search_local_rings, options.normal_search_tolerance);
    if (!verdict.ran) break;
    run.Say(pass->Prefix() + " normal search round " + std::to_string(round + 1) + ": " + std::to_string(ns.moved) +
            " moved (median " + std::to_string(ns.median_move) + " m); " + verdict.Brief() +
            (verdict.kept ? ", kept" : ", dropped"));
    if (!verdict.kept) break;
    ++pass->report.normal_search_rounds;
    pass->report.normal_search_local_windows += verdict.local_windows;
  }
}

}  // namespace facets
