// Stage "wall corners" (the finest level's last pass, aerial starts): the edges walls
// stretched are split (a quality pass, then the level adjusted again); each vertical
// corner where two planar walls meet gets its band of crumpled vertices laid onto the
// two walls and onto their line (refine/wall_corners.h), and walls' feet and eaves
// likewise, one crease at a time, each a trial (engine/pipeline/trial.h) that is left
// when it makes triangles cross or fold.
#pragma once

#include "engine/pipeline/run_context.h"

namespace facets {

void LayWallCorners(const RunContext& run, LevelPass* pass);

}  // namespace facets
