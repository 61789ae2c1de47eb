#include "engine/pipeline/start_stage.h"

#include <algorithm>
#include <stdexcept>
#include <string>
#include <vector>

#include "engine/solver/window_adjustment.h"
#include "engine/start/start_tiepoints.h"

namespace facets {
namespace {

double Median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

double ChooseStartHeight(const ImageBlock& block, const RegionOfInterest& roi, const ReconstructionOptions& options) {
  if (options.start_height) return *options.start_height;
  if (block.mean_height) return *block.mean_height;
  std::vector<double> z;
  for (const auto& p : block.points) {
    if (p.xyz.x() >= roi.min.x() && p.xyz.x() <= roi.max.x() && p.xyz.y() >= roi.min.y() &&
        p.xyz.y() <= roi.max.y()) {
      z.push_back(p.xyz.z());
    }
  }
  if (!z.empty()) return Median(z);
  throw std::runtime_error("no start height: give one, or a mean terrain height in the project, or tie points");
}

// The tie points inside the region and the mean projection centre, for the fitted start
// plane; nullopt keeps the horizontal plane (ReconstructionOptions::start_plane).
std::optional<FittedPlane> ChooseFittedPlane(const ImageBlock& block, const RegionOfInterest& roi,
                                             const ReconstructionOptions& options) {
  using Mode = ReconstructionOptions::StartPlane;
  if (options.start_height || options.start_plane == Mode::kHorizontal) return std::nullopt;
  std::vector<Eigen::Vector3d> points;
  for (const auto& p : block.points) {
    if (roi.Contains(p.xyz)) points.push_back(p.xyz);
  }
  Eigen::Vector3d viewpoint = Eigen::Vector3d::Zero();
  for (const auto& image : block.images) viewpoint += image.ProjectionCentre();
  viewpoint /= static_cast<double>(std::max<size_t>(1, block.images.size()));
  if (options.start_plane == Mode::kFitted) return FitStartPlane(points, viewpoint);  // throws when unusable
  if (points.size() < 10) return std::nullopt;
  try {
    const FittedPlane plane = FitStartPlane(points, viewpoint);
    if (plane.tilt_deg > options.fitted_plane_min_tilt_deg) return plane;
  } catch (const std::runtime_error&) {
    // Collinear tie points: no plane to fit, the horizontal start stays.
  }
  return std::nullopt;
}

Eigen::Vector3d CameraUp(const ImageBlock& block) {
  Eigen::Vector3d up = Eigen::Vector3d::Zero();
  for (const auto& image : block.images) up -= image.cam_from_world.rotation.conjugate() * Eigen::Vector3d::UnitY();
  up /= static_cast<double>(block.images.size());
  return up.norm() >= 0.5 ? Eigen::Vector3d(up.normalized()) : Eigen::Vector3d::UnitZ();
}

std::string DescribeFittedPlane(const FittedPlane& fitted) {
  return "start plane fitted to " + std::to_string(fitted.kept) + " of " + std::to_string(fitted.total) +
         " tie points: tilt " + std::to_string(fitted.tilt_deg) + " deg, RMS " + std::to_string(fitted.rms) +
         " m, extent " + std::to_string((fitted.max_uv - fitted.min_uv).x()) + " x " +
         std::to_string((fitted.max_uv - fitted.min_uv).y()) + " m";
}

TinMesh StartPlane(const RegionOfInterest& roi, double height, double spacing) {
  StartGridOptions grid;
  grid.min = roi.min.head<2>();
  grid.max = roi.max.head<2>();
  grid.spacing = spacing;
  grid.plane_height = height;
  return MakeStartGrid(grid);
}

// The coarsest level's open start: fitted to the tie points, or the plane.
TinMesh OpenStart(const RunContext& run, const StartPlan& plan, ReconstructionReport* report) {
  const ReconstructionOptions& options = run.options;
  const double spacing = run.EdgeLength(run.coarsest);
  const std::vector<Eigen::Vector3d> points = TiePointsOverFootprint(run.block, plan.roi);
  const bool plane_chosen = options.start_height.has_value() || options.lifting_steps > 0;
  if (!UseTiePointStart(options.start, static_cast<int>(points.size()), plane_chosen, options.tiepoint_start)) {
    return StartPlane(plan.roi, plan.start_height, spacing);
  }
  TiePointStartReport fit;
  TinMesh mesh = StartFromTiePoints(points, plan.roi, spacing, options.tiepoint_start, &fit);
  report->start_surface = "tiepoints";
  report->start_detail = fit.Brief();
  return mesh;
}

// The coarsest level's start on a fitted (e.g. facade) plane: the tie points' relief
// along its normal, or the bare plane when too few points lie over it.
TinMesh FittedStart(const RunContext& run, const StartPlan& plan, ReconstructionReport* report) {
  const ReconstructionOptions& options = run.options;
  const double spacing = run.EdgeLength(run.coarsest);
  const std::vector<Eigen::Vector3d> points = TiePointsInRegion(run.block, plan.roi);
  if (!UseTiePointStart(options.start, static_cast<int>(points.size()), false, options.tiepoint_start)) {
    report->start_surface = "fitted plane";
    return MakeFittedPlaneMesh(*plan.fitted, spacing);
  }
  TiePointStartReport fit;
  TinMesh mesh = MakeFittedTiePointMesh(*plan.fitted, points, spacing, options.tiepoint_start, &fit);
  report->start_surface = "tiepoints over the fitted plane";
  report->start_detail = fit.Brief() + " (x, y in the plane, z along its normal)";
  return mesh;
}

// One iteration of the coarsest level from a plane at this height (object lifting).
LiftingTrial TryLiftingHeight(const RunContext& run, const StartPlan& plan, double height) {
  TinMesh mesh = StartPlane(plan.roi, height, run.EdgeLength(run.coarsest));
  AdjustmentOptions one = run.LevelOptions(run.coarsest, 0);
  one.max_iterations = 1;
  one.compute_precision = false;
  LiftingTrial trial;
  trial.height = height;
  try {
    WindowAdjustment adjustment(&mesh, run.images.WholeForRun(run.coarsest), one);
    const WindowReport report = adjustment.Run();
    double sum = 0.0;
    for (auto vh : mesh.vertices()) sum += mesh.point(vh)[2] - height;
    trial.sigma0 = report.sigma0;
    trial.mean_dn = sum / mesh.n_vertices();
    trial.observations = report.observations;
  } catch (const std::runtime_error&) {
    trial.sigma0 = 1e300;  // no image sees this height: not a candidate
  }
  return trial;
}

// Object lifting: start heights over +- lifting_range / 2, one iteration each.
void LiftStartHeight(const RunContext& run, StartPlan* plan, ReconstructionReport* report) {
  const ReconstructionOptions& options = run.options;
  run.Say("stage object lifting: " + std::to_string(options.lifting_steps) + " start heights over " +
          std::to_string(options.lifting_range) + " m");
  for (int s = 0; s < options.lifting_steps; ++s) {
    const double height =
        plan->start_height - 0.5 * options.lifting_range +
        options.lifting_range * (options.lifting_steps == 1 ? 0.5 : s / (options.lifting_steps - 1.0));
    const LiftingTrial trial = TryLiftingHeight(run, *plan, height);
    report->lifting.push_back(trial);
    run.Say("  lifting height " + std::to_string(height) + " m: sigma0 " + std::to_string(trial.sigma0) +
            ", mean displacement " + std::to_string(trial.mean_dn) + " m");
  }
  plan->start_height = ChooseLiftedHeight(report->lifting);
  run.Say("  lifted start height " + std::to_string(plan->start_height) + " m");
}

}  // namespace

StartPlan PlanStart(const ImageBlock& block, const ReconstructionOptions& options) {
  auto say = [&](const std::string& line) {
    if (options.progress) options.progress(line);
  };
  StartPlan plan;
  std::string region_source;
  plan.roi = ChooseRegion(block, options.roi, &region_source);
  say("region: " + DescribeRegion(plan.roi) + " (" + region_source + ")");
  plan.camera_up = CameraUp(block);
  // A closed start (objects) replaces the plane; its centre sets the ground pixel.
  if (options.start_closed || !options.closed.mesh_file.empty()) {
    plan.closed = PrepareClosedStart(block, plan.roi, options.closed);
    say(plan.closed->Describe());
    if (plan.closed->constraint_voxel) say("constraint hull: " + plan.closed->constraint_voxel->why);
  }
  plan.start_height = plan.closed ? plan.closed->centre.z() : ChooseStartHeight(block, plan.roi, options);
  Eigen::Vector3d centre = 0.5 * (plan.roi.min + plan.roi.max);
  centre.z() = plan.start_height;
  // A closed start needs no plane; otherwise a facade's tie points tilt it.
  if (!plan.closed) plan.fitted = ChooseFittedPlane(block, plan.roi, options);
  if (plan.fitted) {
    centre = plan.fitted->centre;
    say(DescribeFittedPlane(*plan.fitted));
  }
  if (plan.closed) centre = plan.closed->centre;
  plan.gsd0 = GroundPixel(block, centre);
  return plan;
}

TinMesh MakeStartSurface(const RunContext& run, StartPlan* plan, ReconstructionReport* report) {
  const ReconstructionOptions& options = run.options;
  if (options.lifting_steps > 0 && plan->fitted) {
    run.Say("object lifting skipped: it searches heights of a horizontal plane, the start plane is fitted");
  } else if (options.lifting_steps > 0 && !plan->closed) {
    LiftStartHeight(run, plan, report);
  }
  report->start_height = plan->start_height;
  TinMesh mesh;
  if (plan->closed) {
    mesh = MakeClosedStartMesh(*plan->closed, options.closed, run.EdgeLength(run.coarsest),
                               options.closed.lifting_steps > 0 ? run.images.WholeForRun(run.coarsest)
                                                                : std::vector<LevelImage>{},
                               run.LevelOptions(run.coarsest, 0), &report->lifting,
                               [&run](const std::string& line) { run.Say(line); });
    report->start_surface = "closed";
  } else if (plan->fitted) {
    mesh = FittedStart(run, *plan, report);
  } else {
    mesh = OpenStart(run, *plan, report);
  }
  run.Say("stage start: " + report->start_surface + (report->start_detail.empty() ? "" : ": " + report->start_detail));
  return mesh;
}

}  // namespace facets
