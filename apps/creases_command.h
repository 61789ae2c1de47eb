// `facets creases TIN.ply --edge H --out OUT.ply [--no-corners] [--no-feet] [--no-eaves]
//  [--min-angle DEG] [--no-merge] [--untangle-rounds N]`: the wall crease step of a
// reconstruction (`--wall-corners --wall-feet --wall-eaves`, on in the aerial scene
// preset; refine/wall_corners.h) on a TIN, without images.
//
// Every vertical corner, foot and eave FindWallCorners finds is laid onto its two planes
// (LayCornerOntoWalls), one at a time in the engine's order, and kept unless it leaves
// more crossing triangle pairs or folded faces than before (after at most N rounds of
// untangling). The engine judges each crease by its images too; this command shows what
// the geometry alone does, in a minute instead of a reconstruction's half hour: give it
// the TIN the corner step started from (`facets reconstruct --keep-levels` writes it as
// levels/level_0_creases.ply) and score the output with `facets evaluate --mesh`.
#pragma once

#include <CLI/CLI.hpp>
#include <string>

#include "refine/wall_corners.h"

namespace facets {

struct CreasesArgs {
  std::string tin;
  std::string out;
  // edge_length: the level's target edge length, m (the reconstruction's log); all three
  // kinds of crease on unless left out.
  WallCornerOptions corners = [] {
    WallCornerOptions all;
    all.edge_length = 0.0;
    all.vertical = all.feet = all.eaves = true;
    return all;
  }();
  int untangle_rounds = 4;
};

struct CreasesSummary {
  int found = 0, laid = 0, left = 0;
  int crossing_before = 0, crossing_after = 0, folded_before = 0, folded_after = 0;
};

// Throws std::runtime_error / std::invalid_argument naming the file or the option.
CreasesSummary RunCreases(const CreasesArgs& args, std::ostream& log);

void AddCreasesCommand(CLI::App& app);

}  // namespace facets
