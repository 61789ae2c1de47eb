// `facets creases TIN.ply --edge H --out OUT.ply [--no-corners] [--no-feet] [--no-eaves]
//  [--min-angle DEG] [--untangle-rounds N]`: the crease step of --thorough-walls
// (mesh/wall_corners.h) on a TIN, without images.
//
// Every vertical corner, foot and eave FindWallCorners finds is laid onto its two planes
// (LayCornerOntoWalls), one at a time in the engine's order, and kept unless it leaves
// more crossing triangle pairs or folded faces than before (after at most N rounds of
// untangling). The engine judges each crease by its images too; this command shows what
// the geometry alone does, in a minute instead of a reconstruction's half hour: give it
// the TIN the corner step started from (`facets reconstruct --keep-levels` writes it as
// levels/level_0_creases.ply) and score the output with `facets evaluate --mesh`
// (docs/EXPERIMENTS.md, session 34).
#pragma once

#include <CLI/CLI.hpp>
#include <string>

namespace facets {

struct CreasesArgs {
  std::string tin;
  std::string out;
  double edge = 0.0;  // the level's target edge length, m (the reconstruction's log)
  bool no_corners = false, no_feet = false, no_eaves = false;
  double min_angle = 0.0;  // 0: WallCornerOptions' default
  bool no_merge = false;   // WallCornerOptions::merge_wall_pieces off
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
