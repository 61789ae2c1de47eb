// What the stages of one reconstruction share: the run (block, options, level images,
// the start's geometry, the ground pixel) and the pass over one pyramid level (its TIN,
// its adjustment and its report). Each stage is a function of these two.
#pragma once

#include <cmath>
#include <optional>
#include <string>

#include "engine/pipeline/level_images_stage.h"
#include "engine/pipeline/reconstruction.h"
#include "engine/start/start_closed.h"
#include "engine/start/start_fitted_plane.h"
#include "mesh/tin.h"

namespace facets {

struct RunContext {
  const ImageBlock& block;
  const ReconstructionOptions& options;
  const LevelImageSource& images;
  const std::optional<ClosedStart>& closed;   // closed start (objects)
  const std::optional<FittedPlane>& fitted;   // start plane fitted to a facade
  double gsd0 = 0.0;                          // ground pixel of the original images, m
  int coarsest = 0;
  int finest = 0;
  RunProfile* profile = nullptr;  // the report's: each stage clocks itself into it

  void Say(const std::string& line) const {
    if (options.progress) options.progress(line);
  }
  // Ground pixel of a pyramid level (m).
  double GroundPixel(int level) const { return gsd0 * std::pow(2.0, level); }
  // Target TIN edge of a level (m): kSubdivisions grey facets of facet_pixels pixels.
  double EdgeLength(int level) const { return kSubdivisions * options.facet_pixels * gsd0 * std::pow(2.0, level); }
  // The window adjustment's options on a level; in a V-cycle (cycle > 0) with its robust
  // weights.
  AdjustmentOptions LevelOptions(int level, int cycle) const;
};

// One pass over a level: the descent's or a V-cycle's.
struct LevelPass {
  int level = 0;
  int cycle = 0;           // 0: the descent; 1..: the V-cycles
  bool last = false;       // the run's last pass
  AdjustmentOptions adjustment;
  TinMesh* mesh = nullptr;
  LevelAdjustment adjusted;  // the level's adjustment as the stages left it
  LevelReport report;

  bool Finest(const RunContext& run) const { return level == run.finest; }
  // "  level L" for progress lines.
  std::string Prefix() const { return "  level " + std::to_string(level); }
  // Clocks one stage of this pass while alive (RunProfile::Stage).
  RunProfile::Scope Clock(const RunContext& run, const std::string& stage) const {
    return run.profile->Stage(level, cycle, stage);
  }
  // After the finest level's adjustment, moves of vertices that keep the topology move
  // only the products' surface points: the tessellation follows the TIN.
  void UpdateProductsSurface();
};

}  // namespace facets
