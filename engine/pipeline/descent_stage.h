// Stage "descent": the TIN one pyramid level down (quaternary subdivision keeping the
// shape and its creases, a quality pass splitting what walls stretched, tangential
// smoothing on the creased G1 surface), or, at the top of a V-cycle, a coarser level's
// TIN put back onto the finished finest surface.
#pragma once

#include "engine/pipeline/run_context.h"
#include "engine/pipeline/v_cycle.h"
#include "mesh/tessellation.h"

namespace facets {

// Refines *pass.mesh from level + 1 to pass.level; returns the smoothing's vertex moves.
int DescendOneLevel(const RunContext& run, LevelPass* pass);

// Moves *pass.mesh (a coarser level's TIN) along its normals onto `finest_surface`.
ProjectionReport GoBackUp(const RunContext& run, LevelPass* pass, const Tessellation& finest_surface);

}  // namespace facets
