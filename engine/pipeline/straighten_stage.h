// Stage "straighten": a crease skew to the grid (a ridge or eave drawn as a zigzag of
// edges) has its vertex chains put onto the crease's line (StraightenCreaseChains),
// each round a trial (engine/pipeline/trial.h), up to straighten_rounds while they fit
// better; each round refits the lines to the surface the last one left. Not for closed
// starts.
#pragma once

#include "engine/pipeline/run_context.h"

namespace facets {

void StraightenCreases(const RunContext& run, LevelPass* pass);

}  // namespace facets
