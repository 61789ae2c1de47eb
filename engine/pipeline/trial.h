// The one trial mechanism of the stages that move vertices after a level's adjustment
// (search rounds, crease straightening, wall corners, feet and eaves, lips): propose a
// move, adjust the level again around it, keep it when the images agree.
//
// The level is adjusted again as a whole (local_rings -1, judged by the level's sigma0)
// or only in the windows over the faces within local_rings edge rings of the moved
// vertices (judged by their own sigma0 before and after, engine/pipeline/local_readjustment.h).
// A proposal kept whatever sigma0 does (tolerance kKeptWhateverSigma0) is adjusted again
// the same way but not judged.
#pragma once

#include <vector>

#include "engine/pipeline/run_context.h"

namespace facets {

// A tolerance at which a proposal is kept whatever sigma0 does: its local re-adjustment
// runs without the two probes (each one linearisation of its windows), and the verdict
// gives the level's fit over the local windows' core faces before and after
// (LevelAdjustment::face_fit).
constexpr double kKeptWhateverSigma0 = 1.0;

struct TrialVerdict {
  bool ran = true;         // false: no window to adjust (nothing moved)
  bool judged = true;      // false: kept whatever sigma0 does
  bool kept = false;
  double was_sigma0 = 0.0;
  double now_sigma0 = 0.0;
  int local_windows = 0;   // 0: the whole level was adjusted again

  // "sigma0 NOW against WAS[ (N local windows)]"
  std::string Brief() const;
};

// *pass.mesh holds the proposal, `before` the surface it replaced. Kept when sigma0
// after < sigma0 before x (1 + tolerance), or whenever tolerance >= kKeptWhateverSigma0:
// pass.adjusted becomes the new adjustment; else *pass.mesh is `before` again.
TrialVerdict JudgeProposal(const RunContext& run, LevelPass* pass, TinMesh before, int local_rings,
                           double tolerance);

// Crossing triangle pairs and folded faces of a TIN: a proposal may not add any.
struct SurfaceFaults {
  int crossing = 0;
  int folded = 0;
  bool WorseThan(const SurfaceFaults& before) const {
    return crossing > before.crossing || folded > before.folded;
  }
};
SurfaceFaults CountSurfaceFaults(const RunContext& run, const TinMesh& mesh);

// The vertices a trial's untangling may move: those the proposal changed from `before`
// (moved, inserted, or on a face it split or flipped: VerticesChangedFrom), grown by
// kTrialUntangleRings edge rings. The untangling grows its
// regions by at most 4 rings from the corners of a crossing face (UntangleSelfIntersections
// with 4 rounds), and a new crossing has a face with a moved corner: 8 rings hold them with
// room, and keep the trial's re-adjustment to the windows around the proposal instead of
// every window that holds an older crossing or fold of the level.
constexpr int kTrialUntangleRings = 8;
std::vector<bool> TrialNeighbourhood(const TinMesh& mesh, const TinMesh& before);

// A proposal that adds faults is untangled within its neighbourhood (at most `rounds`
// rounds of UntangleSelfIntersections, TrialNeighbourhood); returns the faults left.
SurfaceFaults UntangleNewFaults(const RunContext& run, TinMesh* mesh, const TinMesh& before_mesh,
                                const SurfaceFaults& before, int rounds);

}  // namespace facets
