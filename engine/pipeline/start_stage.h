// Stage "start": the region of interest, the kind of start (closed for objects, a plane
// fitted to a facade's tie points, else a height), the ground pixel of the original
// images; then, with the level images, object lifting and the coarsest level's TIN.
#pragma once

#include <optional>

#include "engine/pipeline/reconstruction.h"
#include "engine/pipeline/region_choice.h"
#include "engine/pipeline/run_context.h"
#include "engine/start/start_closed.h"
#include "engine/start/start_fitted_plane.h"
#include "io/image_block.h"
#include "mesh/tin.h"

namespace facets {

struct StartPlan {
  RegionOfInterest roi;
  std::optional<ClosedStart> closed;
  std::optional<FittedPlane> fitted;
  double start_height = 0.0;  // local Z of the start plane, or the closed start's centre
  double gsd0 = 0.0;          // ground pixel of the original images at the start's centre (m)
  // The images' mean up (minus their y axes), unit; Z when they cancel out.
  Eigen::Vector3d camera_up = Eigen::Vector3d::UnitZ();
};

// Throws std::runtime_error when there is no region and no height to start from.
StartPlan PlanStart(const ImageBlock& block, const ReconstructionOptions& options);

// Object lifting (when asked) and the coarsest level's TIN; records the lifting
// trials, the start height and the kind of start in *report.
TinMesh MakeStartSurface(const RunContext& run, StartPlan* plan, ReconstructionReport* report);

}  // namespace facets
