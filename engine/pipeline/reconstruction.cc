#include "engine/pipeline/reconstruction.h"

#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <utility>

#include "engine/pipeline/descent_stage.h"
#include "engine/pipeline/level_images_stage.h"
#include "engine/pipeline/lips_stage.h"
#include "engine/pipeline/run_context.h"
#include "engine/pipeline/search_stage.h"
#include "engine/pipeline/start_stage.h"
#include "engine/pipeline/straighten_stage.h"
#include "engine/pipeline/validity_stage.h"
#include "engine/pipeline/wall_corners_stage.h"

namespace facets {
namespace {

double Seconds(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// The passes over the levels as (level, cycle): the descent coarsest..finest, then each
// V-cycle from v_cycle_level down to the finest again.
std::vector<std::pair<int, int>> PlanPasses(const RunContext& run) {
  std::vector<std::pair<int, int>> passes;
  for (int level = run.coarsest; level >= run.finest; --level) passes.emplace_back(level, 0);
  const int cycle_top = std::min(run.options.v_cycle_level, run.coarsest);
  if (cycle_top > run.finest) {
    for (int c = 1; c <= run.options.v_cycles; ++c) {
      for (int level = cycle_top; level >= run.finest; --level) passes.emplace_back(level, c);
    }
  } else if (run.options.v_cycles > 0) {
    run.Say("v-cycles skipped: no level above the finest to go back to");
  }
  return passes;
}

// The level's window adjustment. With the tie-point start, the coarsest level may not
// take a node further than start_step_cap_pixels of its ground pixels from the height
// its tie points gave it.
void AdjustLevel(const RunContext& run, LevelPass* pass, bool cap_steps) {
  TinMesh& mesh = *pass->mesh;
  std::vector<Eigen::Vector3d> start_points;
  if (cap_steps) {
    for (auto vh : mesh.vertices()) start_points.push_back(ToEigen(mesh.point(vh)));
  }
  pass->adjusted = AdjustLevelInWindows(&mesh, run.images.ForWindows(pass->level), pass->adjustment,
                                        run.options.windows, pass->Finest(run), run.options.progress);
  if (!cap_steps) return;
  const double cap = run.options.start_step_cap_pixels * run.GroundPixel(pass->level);
  int capped = 0;
  for (auto vh : mesh.vertices()) {
    const Eigen::Vector3d step = ToEigen(mesh.point(vh)) - start_points[vh.idx()];
    if (step.norm() <= cap) continue;
    mesh.set_point(vh, ToOpenMesh(start_points[vh.idx()] + step * (cap / step.norm())));
    ++capped;
  }
  UpdateVertexNormals(&mesh);
  run.Say(pass->Prefix() + ": " + std::to_string(capped) + " nodes held within " + std::to_string(cap) +
          " m of their tie-point heights");
}

std::string AdjustLine(const RunContext& run, const LevelPass& pass, size_t index, size_t count) {
  return "stage adjust: level " + std::to_string(pass.level) + " (" + std::to_string(index + 1) + "/" +
         std::to_string(count) + (pass.cycle > 0 ? ", v-cycle " + std::to_string(pass.cycle) : "") + "), " +
         std::to_string(pass.mesh->n_faces()) + " faces, ground pixel " +
         std::to_string(run.GroundPixel(pass.level)) + " m, break-off " + std::to_string(pass.adjustment.break_off) +
         " m";
}

// The level's refinement after its adjustment: search rounds, straightening, wall
// corners (the last pass), unseen vertices relaxed, lips, the visual hull, untangling.
void RefineLevel(const RunContext& run, LevelPass* pass, LevelSearch* search) {
  {
    const auto clock = pass->Clock(run, "search rounds");
    SearchRounds(run, pass, search);
  }
  {
    const auto clock = pass->Clock(run, "straighten");
    StraightenCreases(run, pass);
  }
  const ReconstructionOptions& options = run.options;
  if ((options.wall_corners || options.wall_feet || options.wall_eaves) && pass->last && !run.closed && !run.fitted) {
    const auto clock = pass->Clock(run, "wall corners");
    LayWallCorners(run, pass);
  }
  {
    const auto clock = pass->Clock(run, "relax unseen");
    // Not on a closed start's finest level: its rims, seen edge-on, count as unseen.
    const bool relax_now = pass->level > run.finest || !run.closed;
    if (relax_now && RelaxUnseen(run, pass) > 0 && pass->Finest(run)) pass->UpdateProductsSurface();
  }
  {
    const auto clock = pass->Clock(run, "lips");
    LayUnseenLips(run, pass);
  }
  const auto clock = pass->Clock(run, "validity");
  HoldInsideVisualHull(run, pass);
  CloseLevelReport(run, pass, UntangleCrossings(run, pass));
}

void SayLevelDone(const RunContext& run, const LevelPass& pass) {
  const LevelReport& r = pass.report;
  run.Say(pass.Prefix() + ": " + std::to_string(r.windows.size()) + " windows in " + std::to_string(r.window_groups) +
          " groups, sigma0 " + std::to_string(r.window.sigma0));
  if (r.windows.size() != 1) return;
  for (const auto& it : r.window.iterations) {
    run.Say(pass.Prefix() + " iteration " + std::to_string(it.iteration) + ": sigma0 " + std::to_string(it.sigma0) +
            ", max dn " + std::to_string(it.max_dn_interior) + " m, " + std::to_string(it.observations) +
            " observations, " + std::to_string(it.cg_iterations) + " CG iterations");
  }
}

// One pass: descent (or back up for a V-cycle), search, adjustment, refinement.
void RunPass(const RunContext& run, LevelPass* pass, size_t index, size_t count, bool cap_steps,
             TinMesh* cycle_top_tin, Reconstruction* result) {
  const auto level_start = std::chrono::steady_clock::now();
  pass->adjustment = run.LevelOptions(pass->level, pass->cycle);
  // Per-vertex sigma and the residuals' correlation reach the products from the last pass
  // only, which adjusts every vertex again: the passes before it skip both.
  if (!pass->last) {
    pass->adjustment.compute_precision = false;
    pass->adjustment.residual_correlation = false;
  }
  LevelReport& r = pass->report;
  if (pass->cycle > 0 && pass->level == std::min(run.options.v_cycle_level, run.coarsest)) {
    const auto clock = pass->Clock(run, "back up");
    *pass->mesh = std::move(*cycle_top_tin);
    r.projection = GoBackUp(run, pass, result->tessellation);
  } else if (pass->level != run.coarsest) {
    const auto clock = pass->Clock(run, "descent");
    r.smoothed = DescendOneLevel(run, pass);
  }
  r.cycle = pass->cycle;
  LevelSearch search(run, pass);
  {
    const auto clock = pass->Clock(run, "search before");
    SearchBeforeLevel(run, pass, &search);
  }
  r.level = pass->level;
  r.ground_pixel = run.GroundPixel(pass->level);
  r.edge_length = run.EdgeLength(pass->level);
  r.break_off = pass->adjustment.break_off;
  r.vertices = static_cast<int>(pass->mesh->n_vertices());
  r.faces = static_cast<int>(pass->mesh->n_faces());
  run.Say(AdjustLine(run, *pass, index, count));
  {
    const auto clock = pass->Clock(run, "adjust");
    AdjustLevel(run, pass, cap_steps);
  }
  RefineLevel(run, pass, &search);
  if (run.options.level_done) run.options.level_done(pass->level, *pass->mesh);
  SayLevelDone(run, *pass);
  r.seconds = Seconds(level_start);
}

// The finest level's products: surface, grey values and per-vertex precision.
void TakeFinestLevel(LevelPass* pass, Reconstruction* result) {
  result->tessellation = std::move(pass->adjusted.tessellation);
  result->grey = std::move(pass->adjusted.grey);
  result->vertex_sigma = pass->report.window.vertex_sigma;
  result->vertex_views = pass->report.window.vertex_views;
  result->vertex_flags = pass->report.window.vertex_flags;
}

void RunPasses(const RunContext& run, TinMesh* mesh, Reconstruction* result) {
  const std::vector<std::pair<int, int>> passes = PlanPasses(run);
  const int cycle_top = std::min(run.options.v_cycle_level, run.coarsest);
  TinMesh cycle_top_tin;  // the TIN the last pass at cycle_top left
  for (size_t k = 0; k < passes.size(); ++k) {
    LevelPass pass;
    pass.level = passes[k].first;
    pass.cycle = passes[k].second;
    pass.last = k + 1 == passes.size();
    pass.mesh = mesh;
    const bool cap_steps = run.options.start_step_cap_pixels > 0.0 && pass.level == run.coarsest &&
                           pass.level != run.finest && pass.cycle == 0 &&
                           result->report.start_surface == "tiepoints";
    RunPass(run, &pass, k, passes.size(), cap_steps, &cycle_top_tin, result);
    if (pass.Finest(run)) TakeFinestLevel(&pass, result);
    result->report.levels.push_back(std::move(pass.report));
    if (pass.level == cycle_top && pass.cycle < run.options.v_cycles) cycle_top_tin = *mesh;
  }
}

}  // namespace

AdjustmentOptions RunContext::LevelOptions(int level, int cycle) const {
  AdjustmentOptions adjustment = options.adjustment;
  if (cycle > 0) {
    adjustment.robust_k = options.v_cycle_robust_k;
    adjustment.reject_k = options.v_cycle_robust_k > 0.0 ? options.v_cycle_reject_k : 0.0;
  }
  adjustment.break_off = options.break_off_gsd > 0.0 ? options.break_off_gsd * gsd0 * std::pow(2.0, level)
                                                      : adjustment.break_off * std::pow(2.0, level);
  if (adjustment.max_step == 0.0) adjustment.max_step = 0.5 * EdgeLength(level);
  adjustment.compute_precision = options.adjustment.compute_precision && level == finest;
  adjustment.clocks = profile->window_clocks();
  if (closed) adjustment.rounded_ridges = false;
  return adjustment;
}

Reconstruction Reconstruct(const ImageBlock& block, const ReconstructionOptions& options) {
  options.Check();
  return Reconstruct(CheckBlock(block, options.roi, [&options](const std::string& line) {
                       if (options.progress) options.progress(line);
                     }),
                     options);
}

Reconstruction Reconstruct(const CheckedImageBlock& checked, const ReconstructionOptions& options) {
  options.Check();
  const auto start = std::chrono::steady_clock::now();
  const ImageBlock& block = checked.block;
  if (block.images.size() < 2) throw std::runtime_error("reconstruction needs at least 2 images");
  auto say = [&options](const std::string& line) {
    if (options.progress) options.progress(line);
  };
  Reconstruction result;
  result.report.geometry = checked.geometry;
  RunProfile& profile = result.report.profile;
  const ClockReading run_start = ReadClocks();
  StartPlan plan = PlanStart(block, options);
  profile.AddStage(-1, 0, "start", run_start);
  result.report.camera_up = plan.camera_up;
  const ClockReading images_start = ReadClocks();
  const LevelImageSource images(block, options, say);
  profile.AddStage(-1, 0, "images", images_start);
  result.report.seconds_images = images.seconds();
  result.report.images_cached = images.cached();
  result.channels = images.channels();
  const RunContext run{block, options, images, plan.closed, plan.fitted, plan.gsd0, options.levels - 1,
                       options.finest_level, &profile};
  TinMesh mesh;
  {
    const auto clock = profile.Stage(-1, 0, "start");
    mesh = MakeStartSurface(run, &plan, &result.report);
  }
  if (NormalSearchOn(run)) say("normal search: steep vertices before each finer level");
  RunPasses(run, &mesh, &result);
  result.mesh = std::move(mesh);
  if (options.flatten_crossing_facets) {
    const auto clock = profile.Stage(-1, 0, "products");
    const auto part = profile.Part("flatten crossing facets");
    result.report.facet_crossings = FlattenCrossingFacets(result.mesh, &result.tessellation);
    say("surface facets: " + result.report.facet_crossings.Brief());
  }
  const ClockReading run_end = ReadClocks();
  profile.SetTotal({run_end.wall - run_start.wall, run_end.cpu - run_start.cpu});
  result.report.seconds_total = Seconds(start);
  say("done: " + result.report.BriefReport());
  return result;
}
double ChooseLiftedHeight(const std::vector<LiftingTrial>& trials) {
  auto valid = [](const LiftingTrial& t) { return t.sigma0 < 1e299 && t.observations > 0; };
  double best_sigma = 1e300, best_height = std::numeric_limits<double>::quiet_NaN();
  for (size_t i = 0; i + 1 < trials.size(); ++i) {
    const LiftingTrial& low = trials[i];
    const LiftingTrial& high = trials[i + 1];
    if (!valid(low) || !valid(high) || !(low.mean_dn > 0 && high.mean_dn <= 0)) continue;
    const double sigma = std::min(low.sigma0, high.sigma0);
    if (sigma < best_sigma) {
      best_sigma = sigma;
      best_height = low.height + (high.height - low.height) * low.mean_dn / (low.mean_dn - high.mean_dn);
    }
  }
  if (std::isfinite(best_height)) return best_height;
  for (const LiftingTrial& t : trials) {
    if (valid(t) && t.sigma0 < best_sigma) {
      best_sigma = t.sigma0;
      best_height = t.height + t.mean_dn;
    }
  }
  if (!std::isfinite(best_height)) throw std::runtime_error("object lifting: no image sees any of the trial heights");
  return best_height;
}

void ReconstructionOptions::Check() const {
  auto fail = [](const std::string& what) {
    throw std::invalid_argument("reconstruction options: " + what);
  };
  if (levels < 1 || levels > 10) fail("levels must lie in 1..10");
  if (finest_level < 0 || finest_level >= levels) fail("finest_level must lie in 0..levels-1");
  if (!(facet_pixels > 0.5)) fail("facet_pixels must be > 0.5");
  if (lifting_steps < 0) fail("lifting_steps must be >= 0");
  if (!(break_off_gsd >= 0.0)) fail("break_off_gsd must be >= 0");
  if (tangential_smoothing < 0 || tangential_smoothing > 10) fail("tangential_smoothing must lie in 0..10");
  if (straighten_rounds < 0 || straighten_rounds > 10) fail("straighten_rounds must lie in 0..10");
  if (v_cycles < 0 || v_cycles > 10) fail("v_cycles must lie in 0..10");
  if (normal_search_local_rings < -1) fail("normal_search_local_rings must be >= -1");
  if (straighten_local_rings < -1) fail("straighten_local_rings must be >= -1");
  if (!(straighten_tolerance >= 0.0 && straighten_tolerance <= 1.0)) fail("straighten_tolerance must lie in 0..1");
  if (v_cycle_rounds_last_level < -1) fail("v_cycle_rounds_last_level must be >= -1");
  if (wall_corners_local_rings < -1) fail("wall_corners_local_rings must be >= -1");
  if (!(wall_corners_tolerance >= 0.0 && wall_corners_tolerance <= 1.0)) fail("wall_corners_tolerance must lie in 0..1");
  if (!(wall_corner_min_angle_deg >= 45.0 && wall_corner_min_angle_deg < 90.0))
    fail("wall_corner_min_angle_deg must lie in [45, 90)");
  if (v_cycles > 0 && v_cycle_level < 1) fail("v_cycle_level must be >= 1 (a level above the finest)");
  if (!(v_cycle_robust_k >= 0.0)) fail("v_cycle_robust_k must be >= 0");
  if (v_cycle_robust_k > 0.0 && !(v_cycle_reject_k > v_cycle_robust_k)) fail("v_cycle_reject_k must exceed v_cycle_robust_k");
  if (!(normal_search_tolerance >= 0.0 && normal_search_tolerance <= 1.0)) fail("normal_search_tolerance must lie in 0..1");
  if (lifting_steps > 0 && !(lifting_range > 0)) fail("lifting_range must be > 0");
  if (roi && !(roi->max.array() > roi->min.array()).head<2>().all()) {
    fail("region of interest is empty");
  }
  adjustment.Check();
  windows.Check();
  tiepoint_start.Check();
}

}  // namespace facets
