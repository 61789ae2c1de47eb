#include "engine/pipeline/lips_stage.h"

#include <sstream>
#include <utility>

#include "engine/pipeline/hidden_vertices.h"
#include "engine/pipeline/trial.h"
#include "mesh/surface_validity.h"
#include "refine/unseen_lips.h"

namespace facets {
namespace {

// A laid lip: the faults it left after flattening its rim and untangling.
struct LaidLip {
  LipFold fold;
  SurfaceFaults laid;     // right after laying (and flattening)
  SurfaceFaults now;      // after the untangling
  int flattened = 0;      // wall vertices projected onto the plane
  int untangled = 0;      // vertices the untangling moved
};

// "  level L: lip|pocket at (x, y, z), N vertices"
std::ostringstream Describe(const LevelPass& pass, const LipFold& fold) {
  std::ostringstream line;
  line.precision(3);
  line << std::fixed << pass.Prefix() << ": " << (fold.in_front > 0 ? "lip" : "pocket") << " at (" << fold.centre.x()
       << ", " << fold.centre.y() << ", " << fold.centre.z() << "), " << fold.vertices << " vertices";
  return line;
}

LaidLip LayLip(const RunContext& run, TinMesh* mesh, const TinMesh& before, const UnseenLip& lip,
               const LipFoldOptions& lip_options, const SurfaceFaults& faults) {
  LaidLip laid;
  laid.fold = LayLipOntoWall(mesh, lip, lip_options.embedding_iterations);
  UpdateVertexNormals(mesh);
  laid.now = CountSurfaceFaults(run, *mesh);
  // Faces folded where the laid sheet meets the held wall: their wall corners within the
  // front tolerance go onto the plane.
  if (laid.now.folded > faults.folded) {
    laid.flattened = FlattenFoldedRim(mesh, lip, FoldedFaces(before), lip_options.front_tolerance);
    if (laid.flattened > 0) {
      UpdateVertexNormals(mesh);
      laid.now = CountSurfaceFaults(run, *mesh);
    }
  }
  laid.laid = laid.now;
  // Crossings or folds left after the flattening: the untangling's first round smooths
  // the corners of folded faces.
  if (laid.now.WorseThan(faults) && run.options.fold_lips_untangle_rounds > 0) {
    const auto clock = run.profile->Part("untangling");
    const std::vector<bool> movable = TrialNeighbourhood(*mesh, before);
    const UntangleReport untangle = UntangleSelfIntersections(mesh, run.options.fold_lips_untangle_rounds, &movable);
    UpdateVertexNormals(mesh);
    laid.now.crossing = untangle.pairs_after;
    laid.now.folded = CountFoldedFaces(*mesh);
    laid.untangled = untangle.vertices_moved;
  }
  return laid;
}

std::string LeftLine(const LevelPass& pass, const LaidLip& laid, const SurfaceFaults& faults) {
  std::ostringstream line = Describe(pass, laid.fold);
  line << ": laid onto the wall it makes " << laid.laid.crossing - faults.crossing << " crossing pairs";
  if (laid.now.crossing != laid.laid.crossing || laid.untangled > 0) {
    line << " (" << laid.now.crossing - faults.crossing << " after untangling)";
  }
  line << " and " << laid.now.folded - faults.folded << " folded faces"
       << (laid.flattened > 0 ? " (" + std::to_string(laid.flattened) + " wall vertices flattened)" : std::string())
       << ", left";
  return line.str();
}

std::string JudgedLine(const LevelPass& pass, const LaidLip& laid, const SurfaceFaults& faults,
                       const TrialVerdict& verdict) {
  const LipFold& fold = laid.fold;
  std::ostringstream line = Describe(pass, fold);
  line << " (" << fold.in_front << " in front), laid onto the wall (normal " << fold.normal.x() << ", "
       << fold.normal.y() << ", " << fold.normal.z() << "; " << fold.support << " seen vertices, rms "
       << fold.plane_rms << " m), max move " << fold.max_move << " m; sigma0 " << verdict.now_sigma0 << " against "
       << verdict.was_sigma0 << " (" << verdict.local_windows << " local windows"
       << (laid.untangled > 0 ? ", " + std::to_string(laid.laid.crossing - faults.crossing) +
                                    " crossing pairs untangled, " + std::to_string(laid.untangled) + " vertices moved"
                              : std::string())
       << (laid.flattened > 0 ? ", " + std::to_string(laid.flattened) + " wall vertices flattened" : std::string())
       << "), " << (verdict.kept ? "kept" : "dropped");
  return line.str();
}

void TryLip(const RunContext& run, LevelPass* pass, const UnseenLip& lip, const LipFoldOptions& lip_options,
            SurfaceFaults* faults) {
  TinMesh& mesh = *pass->mesh;
  TinMesh before = mesh;
  const LaidLip laid = LayLip(run, &mesh, before, lip, lip_options, *faults);
  if (laid.now.WorseThan(*faults)) {
    run.Say(LeftLine(*pass, laid, *faults));
    mesh = std::move(before);
    ++pass->report.lips_dropped;
    return;
  }
  const TrialVerdict verdict =
      JudgeProposal(run, pass, std::move(before), run.options.fold_lips_local_rings, run.options.fold_lips_tolerance);
  run.Say(JudgedLine(*pass, laid, *faults, verdict));
  if (!verdict.kept) {
    ++pass->report.lips_dropped;
    return;
  }
  LevelReport& r = pass->report;
  ++r.lips_folded;
  if (laid.untangled > 0) ++r.lips_untangled;
  if (laid.flattened > 0) ++r.lips_flattened;
  r.lip_vertices_moved += laid.fold.vertices;
  *faults = CountSurfaceFaults(run, mesh);
}

}  // namespace

void LayUnseenLips(const RunContext& run, LevelPass* pass) {
  if (!run.options.fold_lips || run.closed || run.fitted) return;
  LipFoldOptions lip_options;
  lip_options.front_tolerance = 0.15 * run.EdgeLength(pass->level);
  lip_options.max_plane_rms = 0.25 * run.EdgeLength(pass->level);
  const LipSearch search =
      FindUnseenLips(*pass->mesh, VisibleViews(*pass->mesh, run.block, 0.25 * run.EdgeLength(pass->level)), lip_options);
  if (search.groups > 0) {
    run.Say(pass->Prefix() + ": " + std::to_string(search.groups) + " groups of unseen steep or down-facing vertices, " +
            std::to_string(search.lips.size()) + " lips or pockets off a seen wall (" + std::to_string(search.no_wall) +
            " without a wall, " + std::to_string(search.not_free) + " not free)");
  }
  SurfaceFaults faults = search.lips.empty() ? SurfaceFaults{} : CountSurfaceFaults(run, *pass->mesh);
  for (const UnseenLip& lip : search.lips) TryLip(run, pass, lip, lip_options, &faults);
  if (pass->report.lips_folded > 0 && pass->Finest(run)) pass->UpdateProductsSurface();
}

}  // namespace facets
