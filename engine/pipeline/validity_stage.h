// Stage "validity", after each level's adjustment and refinement:
//   - vertices no image saw within a quarter of an edge (a sheet folded under a roof that
//     rose) fall back to the membrane spanned by the seen surface around them;
//   - a closed start from a visual hull: the surface pulled back inside the hull and,
//     when asked, pushed out onto its rims;
//   - triangle pairs that cross (between windows, after splits: the fold guard sees one
//     window's step only) are untangled by local smoothing of their corners;
//   - the level's validity counted for its report: folded faces, crossing pairs, steps
//     the fold guard limited.
#pragma once

#include "engine/pipeline/run_context.h"

namespace facets {

// Relaxes the unseen vertices (ReconstructionOptions::relax_unseen); returns how many.
int RelaxUnseen(const RunContext& run, LevelPass* pass);

// Silhouette constraint of a visual-hull start: the surface may not leave the hull.
void HoldInsideVisualHull(const RunContext& run, LevelPass* pass);

// Untangles crossing pairs (ReconstructionOptions::untangle); returns the pairs left, or
// -1 when it did not run.
int UntangleCrossings(const RunContext& run, LevelPass* pass);

// The level's validity counts and its closing progress lines.
void CloseLevelReport(const RunContext& run, LevelPass* pass, int crossing_left);

}  // namespace facets
