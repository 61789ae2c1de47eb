// Stage "lips" (aerial starts, after each level): lips of the surface in front of a wall
// whose underside no image sees, and pockets behind it that their rims hide
// (refine/unseen_lips.h), are laid onto the plane of the seen wall beside them, one at
// a time, so that one bad lip does not take the others with it. A laid lip whose rim
// folds against the held wall has that rim flattened onto the plane; one that makes
// triangles cross is untangled; one that still adds crossing or folded faces is left;
// the rest are trials (engine/pipeline/trial.h).
#pragma once

#include "engine/pipeline/run_context.h"

namespace facets {

void LayUnseenLips(const RunContext& run, LevelPass* pass);

}  // namespace facets
