#include "engine/pipeline/reconstruction.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <memory>
#include <chrono>
#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>
#include <iomanip>
#include <sstream>
#include <stdexcept>
#include <unordered_map>

#include "engine/pipeline/hidden_vertices.h"
#include "engine/pipeline/local_readjustment.h"
#include "engine/start/start_fitted_plane.h"
#include "mesh/creases.h"
#include "mesh/local_ops.h"
#include "mesh/subdivision.h"
#include "mesh/surface_validity.h"
#include "refine/crease_lines.h"
#include "refine/unseen_lips.h"
#include "refine/wall_corners.h"

namespace facets {
namespace {

double Seconds(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

double Median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

double Percentile(std::vector<double> v, double q) {
  std::sort(v.begin(), v.end());
  return v[static_cast<size_t>(std::clamp(q, 0.0, 1.0) * (v.size() - 1))];
}

RegionOfInterest ChooseRoi(const ImageBlock& block, const ReconstructionOptions& options) {
  if (options.roi) return *options.roi;
  if (block.roi) return *block.roi;
  if (block.points.size() >= 10) {
    // The bulk of the tie points: 2nd to 98th percentile, robust to a few blunders.
    std::vector<double> x, y, z;
    for (const auto& p : block.points) {
      x.push_back(p.xyz.x());
      y.push_back(p.xyz.y());
      z.push_back(p.xyz.z());
    }
    RegionOfInterest roi;
    roi.min = Eigen::Vector3d(Percentile(x, 0.02), Percentile(y, 0.02), Percentile(z, 0.02));
    roi.max = Eigen::Vector3d(Percentile(x, 0.98), Percentile(y, 0.98), Percentile(z, 0.98));
    return roi;
  }
  throw std::runtime_error(
      "no region of interest: the block has none, none was given, and there are fewer "
      "than 10 tie points to derive one from");
}

double ChooseStartHeight(const ImageBlock& block, const RegionOfInterest& roi,
                         const ReconstructionOptions& options) {
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
  throw std::runtime_error(
      "no start height: give one, or a mean terrain height in the project, or tie points");
}

// Mean ground pixel size of the original images at the ROI centre.
double GroundPixel(const ImageBlock& block, const Eigen::Vector3d& centre) {
  std::vector<double> gsd;
  for (const auto& image : block.images) {
    const Camera& camera = block.CameraOf(image);
    const double focal = 0.5 * (camera.FocalX() + camera.FocalY());
    gsd.push_back((centre - image.ProjectionCentre()).norm() / focal);
  }
  return Median(gsd);
}

// The tie points inside the region and the mean projection centre, for the fitted start
// plane; nullopt keeps the horizontal plane (see ReconstructionOptions::start_plane).
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

TinMesh StartPlane(const RegionOfInterest& roi, double height, double spacing) {
  StartGridOptions grid;
  grid.min = roi.min.head<2>();
  grid.max = roi.max.head<2>();
  grid.spacing = spacing;
  grid.plane_height = height;
  return MakeStartGrid(grid);
}

// The coarsest level's start TIN: fitted to the tie points or the plane.
TinMesh StartSurface(const ImageBlock& block, const RegionOfInterest& roi, double height,
                     double spacing, const ReconstructionOptions& options, ReconstructionReport* report) {
  const std::vector<Eigen::Vector3d> points = TiePointsInRegion(block, roi);
  const bool plane_chosen = options.start_height.has_value() || options.lifting_steps > 0;
  if (!UseTiePointStart(options.start, static_cast<int>(points.size()), plane_chosen, options.tiepoint_start)) {
    return StartPlane(roi, height, spacing);
  }
  TiePointStartReport fit;
  TinMesh mesh = StartFromTiePoints(points, roi, spacing, options.tiepoint_start, &fit);
  report->start_surface = "tiepoints";
  report->start_detail = fit.Brief();
  return mesh;
}

}  // namespace

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
  if (std::isnan(polish_robust_k)) fail("polish_robust_k must be a number (negative = no polish)");
  if (polish_robust_k > 0.0 && !(polish_reject_k > polish_robust_k))
    fail("polish_reject_k must exceed polish_robust_k");
  if (lifting_steps < 0) fail("lifting_steps must be >= 0");
  if (!(break_off_gsd >= 0.0)) fail("break_off_gsd must be >= 0");
  if (wall_passes < 0 || wall_passes > 10) fail("wall_passes must lie in 0..10");
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

std::string ReconstructionReport::BriefReport() const {
  std::ostringstream out;
  out << "start height " << start_height << " m; ";
  for (const auto& level : levels) {
    out << "level " << level.level << ": " << level.faces << " faces, "
        << level.window.iterations.size() << " iterations, sigma0 " << level.window.sigma0
        << "; ";
  }
  out << seconds_total << " s";
  return out.str();
}

std::string ReconstructionReport::Json() const {
  using nlohmann::json;
  json j;
  j["start_height"] = start_height;
  j["start_surface"] = start_surface;
  j["camera_up"] = {camera_up.x(), camera_up.y(), camera_up.z()};
  if (!start_detail.empty()) j["start_detail"] = start_detail;
  j["seconds_total"] = seconds_total;
  j["seconds_images"] = seconds_images;
  j["images_cached"] = images_cached;
  if (facet_crossings.pairs_found >= 0) {
    j["facet_crossings"] = {{"pairs_found", facet_crossings.pairs_found},
                            {"pairs_left", facet_crossings.pairs_left},
                            {"rounds", facet_crossings.rounds},
                            {"tin_faces_changed", facet_crossings.faces_changed},
                            {"tin_vertices_weighted", facet_crossings.vertices_weighted},
                            {"unchecked_facets", facet_crossings.unchecked_facets},
                            {"max_node_move", facet_crossings.max_move}};
  }
  for (const auto& t : lifting) {
    j["object_lifting"].push_back({{"height", t.height}, {"sigma0", t.sigma0},
                                   {"mean_dn", t.mean_dn}, {"observations", t.observations}});
  }
  long long observations = 0;
  int iterations = 0, cg = 0;
  for (const auto& level : levels) {
    json l;
    l["level"] = level.level;
    l["ground_pixel"] = level.ground_pixel;
    l["edge_length"] = level.edge_length;
    l["smoothed"] = level.smoothed;
    l["normal_search_rounds"] = level.normal_search_rounds;
    if (level.normal_search_local_windows > 0) l["normal_search_local_windows"] = level.normal_search_local_windows;
    if (level.cycle > 0) {
      l["cycle"] = level.cycle;
      const ProjectionReport& p = level.projection;
      l["v_cycle_projection"] = {{"moved", p.moved},
                                 {"missed", p.missed},
                                 {"limited", p.limited},
                                 {"median_move", p.median_move},
                                 {"max_move", p.max_move}};
    }
    const NormalSearchReport& ns = level.normal_search;
    if (ns.searched > 0) {
      l["normal_search"] = {{"searched", ns.searched},         {"peaks", ns.peaks},
                            {"corner_peaks", ns.corner_peaks}, {"moved", ns.moved},
                            {"limited", ns.limited},           {"median_move", ns.median_move},
                            {"max_move", ns.max_move}};
    }
    const PlanePropagationReport& pp = level.plane_propagation;
    if (pp.sources + pp.targets > 0) {
      l["plane_propagation"] = {{"sources", pp.sources},       {"targets", pp.targets},
                                {"hypotheses", pp.hypotheses}, {"moved", pp.moved},
                                {"limited", pp.limited},       {"iterations", pp.iterations},
                                {"median_move", pp.median_move}, {"max_move", pp.max_move}};
    }
    l["break_off"] = level.break_off;
    l["vertices"] = level.vertices;
    l["faces"] = level.faces;
    l["seconds"] = level.seconds;
    l["folded_faces"] = level.folded_faces;
    l["hull_clamped"] = level.hull_clamped;
    l["hull_unresolved"] = level.hull_unresolved;
    l["hull_rim_pushed"] = level.hull_rim_pushed;
    l["self_intersections"] = level.self_intersections;
    l["fold_limited"] = level.fold_limited;
    l["relaxed_unseen"] = level.relaxed;
    l["lips_folded"] = level.lips_folded;
    l["lip_vertices_moved"] = level.lip_vertices_moved;
    l["lips_dropped"] = level.lips_dropped;
    l["corner_splits"] = level.corner_splits;
    l["corners_found"] = level.corners_found;
    l["corners_laid"] = level.corners_laid;
    l["feet_found"] = level.feet_found;
    l["feet_laid"] = level.feet_laid;
    l["eaves_found"] = level.eaves_found;
    l["eaves_laid"] = level.eaves_laid;
    l["corner_vertices_moved"] = level.corner_vertices_moved;
    l["corners_dropped"] = level.corners_dropped;
    l["lips_untangled"] = level.lips_untangled;
    l["lips_flattened"] = level.lips_flattened;
    l["crossing_pairs_untangled"] = level.crossing_untangled;
    l["untangle_moved_vertices"] = level.untangle_moved;
    l["untangle_membranes"] = level.untangle_membranes;
    l["straighten_passes_kept"] = level.straighten_kept;
    l["straighten_passes_dropped"] = level.straighten_dropped;
    l["straightened_vertices"] = level.straightened;
    if (level.polished) l["sigma0_before_polish"] = level.sigma0_before_polish;
    for (const WallPass& pass : level.wall_passes) {
      l["wall_passes"].push_back({{"splits", pass.splits}, {"flips", pass.flips},
                                  {"faces", pass.faces}, {"sigma0", pass.sigma0}});
    }
    auto window_json = [](const WindowReport& w) {
      json window = {{"converged", w.converged},
                     {"stalled", w.stalled},
                     {"iterations", w.iterations.size()},
                     {"cg_iterations", w.cg_iterations_total},
                     {"observations", w.observations},
                     {"pseudo_observations", w.pseudo_observations},
                     {"background_pixels", w.background},
                     {"rejected", w.rejected},
                     {"rejected_share", w.observations + w.rejected > 0
                                            ? static_cast<double>(w.rejected) / (w.observations + w.rejected)
                                            : 0.0},
                     {"downweighted", w.downweighted},
                     {"silhouette_observations", w.silhouette},
                     {"silhouette_outside", w.silhouette_outside},
                     {"plumb_faces", w.plumb},
                     {"unknowns", w.unknowns},
                     {"redundancy", w.redundancy},
                     {"sigma0", w.sigma0},
                     {"crease_edges", w.crease_edges},
                     {"crease_passes_dropped", w.crease_passes_dropped},
                     {"crease_pass_iterations_dropped", w.crease_pass_iterations_dropped},
                     {"seconds", w.seconds_total},
                     {"seconds_precision", w.seconds_precision},
                     {"precision_computed", w.precision_computed},
                     {"residual_rho_x", w.residual_rho_x},
                     {"residual_rho_y", w.residual_rho_y},
                     {"variance_factor", w.variance_factor}};
      for (const auto& it : w.iterations) {
        window["per_iteration"].push_back(
            {{"iteration", it.iteration},
             {"observations", it.observations},
             {"rays", it.rays},
             {"rect_pixels", it.rect_pixels},
             {"cg_iterations", it.cg_iterations},
             {"sigma0", it.sigma0},
             {"robust_scale", it.robust_scale},
             {"rejected", it.rejected},
             {"silhouette_observations", it.silhouette},
             {"silhouette_outside", it.silhouette_outside},
             {"plumb_faces", it.plumb},
             {"max_dn", {it.max_dn_interior, it.max_dn_border, it.max_dn_corner}},
             {"fold_limited", it.fold_limited},
             {"seconds", {{"cast", it.seconds_cast},
                          {"linearise", it.seconds_linearise},
                          {"solve", it.seconds_solve},
                          {"update", it.seconds_update}}}});
      }
      return window;
    };
    const WindowReport& w = level.window;
    l["summary"] = window_json(w);
    l["summary"].erase("per_iteration");
    l["window_groups"] = level.window_groups;
    for (size_t k = 0; k < level.windows.size(); ++k) {
      json window = window_json(level.windows[k]);
      window["window"] = k;
      if (k < level.window_core_faces.size()) window["core_faces"] = level.window_core_faces[k];
      l["windows"].push_back(window);
    }
    j["levels"].push_back(l);
    observations += w.observations;
    for (const auto& window : level.windows) iterations += static_cast<int>(window.iterations.size());
    cg += w.cg_iterations_total;
  }
  j["totals"] = {{"levels", levels.size()},
                 {"window_iterations", iterations},
                 {"cg_iterations", cg},
                 {"observations_last_iterations", observations},
                 {"sigma0_finest", levels.empty() ? 0.0 : levels.back().window.sigma0}};
  return j.dump(2);
}

Reconstruction Reconstruct(const ImageBlock& block, const ReconstructionOptions& options) {
  options.Check();
  const auto start = std::chrono::steady_clock::now();
  auto say = [&](const std::string& line) {
    if (options.progress) options.progress(line);
  };
  if (block.images.size() < 2) throw std::runtime_error("reconstruction needs at least 2 images");
  Reconstruction result;
  const RegionOfInterest roi = ChooseRoi(block, options);
  {
    Eigen::Vector3d up = Eigen::Vector3d::Zero();
    for (const auto& image : block.images) up -= image.cam_from_world.rotation.conjugate() * Eigen::Vector3d::UnitY();
    up /= static_cast<double>(block.images.size());
    if (up.norm() >= 0.5) result.report.camera_up = up.normalized();
  }
  // A closed start (objects) replaces the plane; its centre sets the ground pixel.
  std::optional<ClosedStart> closed;
  if (options.start_closed || !options.closed.mesh_file.empty()) {
    closed = PrepareClosedStart(block, roi, options.closed);
    say(closed->Describe());
  }
  double start_height = closed ? closed->centre.z() : ChooseStartHeight(block, roi, options);
  Eigen::Vector3d centre = 0.5 * (roi.min + roi.max);
  centre.z() = start_height;
  // A closed start needs no plane; otherwise a facade's tie points tilt it (start_fitted_plane.h).
  std::optional<FittedPlane> fitted;
  if (!closed) fitted = ChooseFittedPlane(block, roi, options);
  if (fitted) {
    centre = fitted->centre;
    say("start plane fitted to " + std::to_string(fitted->kept) + " of " + std::to_string(fitted->total) +
        " tie points: tilt " + std::to_string(fitted->tilt_deg) + " deg, RMS " + std::to_string(fitted->rms) +
        " m, extent " + std::to_string((fitted->max_uv - fitted->min_uv).x()) + " x " +
        std::to_string((fitted->max_uv - fitted->min_uv).y()) + " m");
  }
  if (closed) centre = closed->centre;
  const double gsd0 = GroundPixel(block, centre);
  const int num_levels = options.levels;
  const int finest = options.finest_level;

  // Images and their pyramids; cameras scaled level by level exactly like the images.
  say("stage images: reading " + std::to_string(block.images.size()) + " images, " +
      std::to_string(num_levels) + " pyramid levels" +
      (finest > 0 ? ", adjusted down to level " + std::to_string(finest) : std::string()));
  const auto images_start = std::chrono::steady_clock::now();
  LevelImageStoreOptions store_options;
  store_options.levels = num_levels;
  store_options.first_level = finest;
  store_options.filter = options.filter;
  store_options.colour = options.colour;
  if (options.image_cache_dir) {
    store_options.cache_dir = *options.image_cache_dir;
    store_options.cache_memory_mb = options.image_cache_mb;
  }
  const LevelImageStore store(block, store_options);
  result.report.seconds_images = Seconds(images_start);
  result.report.images_cached = store.cached();
  result.channels = store.channels();
  say("  " + std::string(store.cached() ? "tiled level images in " + store_options.cache_dir
                                        : "level images in memory: " + std::to_string(store.MemoryMb()) + " MB"));
  ImageStorage whole_storage;  // whole coarse images read for object lifting
  auto level_images = [&](int level) { return store.Whole(level, &whole_storage); };
  // Silhouette term (AdjustmentOptions::silhouette_weight): each image's foreground
  // outline as a signed distance, handed to the windows with their images.
  std::vector<SilhouetteView> silhouettes;
  std::unordered_map<int, const SilhouetteView*> silhouette_of;
  if (options.adjustment.silhouette_weight > 0.0) {
    const HullViews views = ReadHullViews(block, options.silhouette_foreground);
    silhouettes.resize(views.masks.size());
    tbb::parallel_for(size_t{0}, views.masks.size(), [&](size_t k) {
      silhouettes[k] = {views.cameras[k], views.cam_from_world[k], SignedDistanceToOutline(views.masks[k])};
    });
    for (size_t k = 0; k < silhouettes.size(); ++k) silhouette_of[block.images[k].image_id] = &silhouettes[k];
    say("  silhouettes: " + std::to_string(silhouettes.size()) + " images, background <= " +
        std::to_string(options.silhouette_foreground.background_max) + ", weight " +
        std::to_string(options.adjustment.silhouette_weight));
  }
  auto window_images = [&](int level) -> WindowImages {
    return [&store, &silhouette_of, level](const Eigen::AlignedBox3d& box, ImageStorage* storage) {
      std::vector<LevelImage> images = store.Seeing(level, box, storage);
      for (LevelImage& image : images) {
        const auto found = silhouette_of.find(image.image_id);
        if (found != silhouette_of.end()) image.silhouette = found->second;
      }
      return images;
    };
  };
  auto edge_length = [&](int level) {
    return kSubdivisions * options.facet_pixels * gsd0 * std::pow(2.0, level);
  };
  int cycle = 0;  // of the level being adjusted: 0 = the descent, 1.. = the V-cycles
  auto level_options = [&](int level) {
    AdjustmentOptions adjustment = options.adjustment;
    if (cycle > 0) {
      adjustment.robust_k = options.v_cycle_robust_k;
      adjustment.reject_k = options.v_cycle_robust_k > 0.0 ? options.v_cycle_reject_k : 0.0;
    }
    adjustment.break_off = options.break_off_gsd > 0.0
                               ? options.break_off_gsd * gsd0 * std::pow(2.0, level)
                               : adjustment.break_off * std::pow(2.0, level);
    if (adjustment.max_step == 0.0) adjustment.max_step = 0.5 * edge_length(level);
    adjustment.compute_precision = options.adjustment.compute_precision && level == finest;
    if (closed) adjustment.rounded_ridges = false;
    return adjustment;
  };

  // Object lifting on the coarsest level (seed 001).
  const int coarsest = num_levels - 1;
  if (options.lifting_steps > 0 && fitted) {
    say("object lifting skipped: it searches heights of a horizontal plane, the start plane is fitted");
  } else if (options.lifting_steps > 0 && !closed) {
    say("stage object lifting: " + std::to_string(options.lifting_steps) + " start heights over " +
        std::to_string(options.lifting_range) + " m");
    for (int s = 0; s < options.lifting_steps; ++s) {
      const double height =
          start_height - 0.5 * options.lifting_range +
          options.lifting_range * (options.lifting_steps == 1 ? 0.5 : s / (options.lifting_steps - 1.0));
      TinMesh mesh = StartPlane(roi, height, edge_length(coarsest));
      AdjustmentOptions one = level_options(coarsest);
      one.max_iterations = 1;
      one.compute_precision = false;
      LiftingTrial trial;
      trial.height = height;
      try {
        WindowAdjustment adjustment(&mesh, level_images(coarsest), one);
        const WindowReport report = adjustment.Run();
        double sum = 0.0;
        for (auto vh : mesh.vertices()) sum += mesh.point(vh)[2] - height;
        trial.sigma0 = report.sigma0;
        trial.mean_dn = sum / mesh.n_vertices();
        trial.observations = report.observations;
      } catch (const std::runtime_error&) {
        trial.sigma0 = 1e300;  // no image sees this height: not a candidate
      }
      result.report.lifting.push_back(trial);
      say("  lifting height " + std::to_string(height) + " m: sigma0 " + std::to_string(trial.sigma0) +
          ", mean displacement " + std::to_string(trial.mean_dn) + " m");
    }
    start_height = ChooseLiftedHeight(result.report.lifting);
    say("  lifted start height " + std::to_string(start_height) + " m");
  }
  result.report.start_height = start_height;

  TinMesh mesh;
  if (closed) {
    mesh = MakeClosedStartMesh(*closed, options.closed, edge_length(coarsest),
                               options.closed.lifting_steps > 0 ? level_images(coarsest) : std::vector<LevelImage>{},
                               level_options(coarsest), &result.report.lifting, say);
    result.report.start_surface = "closed";
  } else if (fitted) {
    mesh = MakeFittedPlaneMesh(*fitted, edge_length(coarsest));
    result.report.start_surface = "fitted plane";
  } else {
    mesh = StartSurface(block, roi, start_height, edge_length(coarsest), options, &result.report);
  }
  say("stage start: " + result.report.start_surface + (result.report.start_detail.empty() ? "" : ": " + result.report.start_detail));
  const bool normal_search = options.normal_search.value_or(!closed && !fitted);
  if (normal_search) {
    say(std::string("normal search: steep vertices") +
        (options.normal_search_options.corners ? " and ramps (corner hypotheses)" : "") + " before each finer level");
  }
  // The passes: the descent coarsest..finest, then each V-cycle top..finest.
  std::vector<std::pair<int, int>> passes;  // (level, cycle)
  for (int level = coarsest; level >= finest; --level) passes.emplace_back(level, 0);
  const int cycle_top = std::min(options.v_cycle_level, coarsest);
  if (cycle_top > finest) {
    for (int c = 1; c <= options.v_cycles; ++c) {
      for (int level = cycle_top; level >= finest; --level) passes.emplace_back(level, c);
    }
  } else if (options.v_cycles > 0) {
    say("v-cycles skipped: no level above the finest to go back to");
  }
  TinMesh cycle_top_tin;  // the TIN the last pass at cycle_top left
  for (size_t pass = 0; pass < passes.size(); ++pass) {
    const int level = passes[pass].first;
    cycle = passes[pass].second;
    const bool last_pass = pass + 1 == passes.size();
    int smoothed = 0;
    const auto level_start = std::chrono::steady_clock::now();
    const AdjustmentOptions adjustment_options = level_options(level);
    ProjectionReport projection;
    if (cycle > 0 && level == cycle_top) {
      // Back up the pyramid: the level's TIN onto the finished finest surface.
      mesh = std::move(cycle_top_tin);
      projection = ProjectAlongNormals(&mesh, result.tessellation, edge_length(level));
      say("stage v-cycle " + std::to_string(cycle) + "/" + std::to_string(options.v_cycles) + ": level " +
          std::to_string(level) + "'s TIN onto the level-" + std::to_string(finest) + " surface, " +
          std::to_string(projection.moved) + " vertices moved (median " + std::to_string(projection.median_move) +
          " m, max " + std::to_string(projection.max_move) + " m), " + std::to_string(projection.missed) +
          " without a hit, " + std::to_string(projection.limited) + " limited by the fold guard");
    } else if (level != coarsest) {
      // One pyramid level down: quaternary subdivision keeps the shape (creases
      // included), the quality pass splits what walls stretched, tangential smoothing
      // on the creased G1 surface evens the triangles out.
      const AdjustmentOptions coarser = level_options(level + 1);  // whose creases the mesh has
      mesh = QuaternarySubdivide(
          mesh, ComputeCornerNormals(mesh, coarser.crease_angle_deg, coarser.rounded_ridges));
      QualityOptions quality;
      quality.target_edge_length = edge_length(level);
      // Two rounds at most: a diverged level (a surface torn into long spikes) must not
      // multiply the faces (seen: 338 -> 4104 faces and 5 minutes).
      quality.max_rounds = 2;
      QualityPass(&mesh, quality);
      UpdateVertexNormals(&mesh);
      if (options.tangential_smoothing > 0) {
        SmoothingOptions smoothing;
        smoothing.iterations = options.tangential_smoothing;
        smoothing.crease_angle_deg = coarser.crease_angle_deg;
        smoothing.rounded_ridges = coarser.rounded_ridges;
        smoothing.fix_boundary = true;
        smoothed = TangentialSmooth(&mesh, smoothing).moved;
        UpdateVertexNormals(&mesh);
      }
    }
    LevelReport level_report;
    level_report.cycle = cycle;
    level_report.projection = projection;
    // The normal search (before the level and in its rounds) reads the level's whole images
    // once; with tiled images they are freed with the level, not kept with the lifting's.
    const bool search_level = normal_search && level != coarsest && level >= options.normal_search_last_level;
    ImageStorage search_storage;
    std::vector<LevelImage> search_images;
    PlanePropagationReport planes;  // of the last search_normals()
    auto search_normals = [&]() {
      if (search_images.empty()) search_images = store.Whole(level, &search_storage);
      NormalSearchReport ns =
          SearchAlongNormals(&mesh, search_images, gsd0 * std::pow(2.0, level), options.normal_search_options);
      if (options.plane_propagation) {
        planes = PropagatePlanes(&mesh, search_images, gsd0 * std::pow(2.0, level), options.plane_propagation_options);
        say("  level " + std::to_string(level) + " plane propagation: " + std::to_string(planes.sources) +
            " vertices lend their plane, " + std::to_string(planes.targets) + " borrow; " +
            std::to_string(planes.hypotheses) + " planes scored, " + std::to_string(planes.moved) +
            " moved in " + std::to_string(planes.iterations) + " iterations (median " +
            std::to_string(planes.median_move) + " m, max " + std::to_string(planes.max_move) + " m), " +
            std::to_string(planes.limited) + " limited by the fold guard");
        ns.moved += planes.moved;  // the rounds go on while either moved something
      }
      return ns;
    };
    if (search_level) {
      level_report.normal_search = search_normals();
      level_report.plane_propagation = planes;
      const NormalSearchReport& ns = level_report.normal_search;
      say("  level " + std::to_string(level) + " normal search: " + std::to_string(ns.searched) +
          " vertices searched, " + std::to_string(ns.peaks) + " peaks" +
          (options.normal_search_options.corners ? " (" + std::to_string(ns.corner_peaks) + " at corners)" : "") + ", " + std::to_string(ns.moved) +
          " moved (median " + std::to_string(ns.median_move) + " m, max " + std::to_string(ns.max_move) +
          " m), " + std::to_string(ns.limited) + " limited by the fold guard");
    }
    level_report.smoothed = smoothed;
    level_report.level = level;
    level_report.ground_pixel = gsd0 * std::pow(2.0, level);
    level_report.edge_length = edge_length(level);
    level_report.break_off = level_options(level).break_off;
    level_report.vertices = static_cast<int>(mesh.n_vertices());
    level_report.faces = static_cast<int>(mesh.n_faces());
    say("stage adjust: level " + std::to_string(level) + " (" + std::to_string(pass + 1) + "/" +
        std::to_string(passes.size()) + (cycle > 0 ? ", v-cycle " + std::to_string(cycle) : "") + "), " +
        std::to_string(mesh.n_faces()) +
        " faces, ground pixel " + std::to_string(level_report.ground_pixel) + " m, break-off " +
        std::to_string(level_report.break_off) + " m");
    // The coarsest level may not take a node further than the cap from the height its
    // tie points gave it (ReconstructionOptions::start_step_cap_pixels).
    const bool cap_steps = options.start_step_cap_pixels > 0.0 && level == coarsest && level != finest &&
                           cycle == 0 && result.report.start_surface == "tiepoints";
    std::vector<Eigen::Vector3d> start_points;
    if (cap_steps) {
      for (auto vh : mesh.vertices()) start_points.push_back(ToEigen(mesh.point(vh)));
    }
    LevelAdjustment adjusted = AdjustLevelInWindows(&mesh, window_images(level), level_options(level),
                                                    options.windows, level == finest, options.progress);
    if (cap_steps) {
      const double cap = options.start_step_cap_pixels * gsd0 * std::pow(2.0, level);
      int capped = 0;
      for (auto vh : mesh.vertices()) {
        const Eigen::Vector3d step = ToEigen(mesh.point(vh)) - start_points[vh.idx()];
        if (step.norm() <= cap) continue;
        mesh.set_point(vh, ToOpenMesh(start_points[vh.idx()] + step * (cap / step.norm())));
        ++capped;
      }
      UpdateVertexNormals(&mesh);
      say("  level " + std::to_string(level) + ": " + std::to_string(capped) + " nodes held within " +
          std::to_string(cap) + " m of their tie-point heights");
    }
    // Vertices no image saw (a sheet folded under a roof that rose) fall back to the
    // membrane spanned by the seen surface around them (mesh/local_ops.h).
    auto relax_unseen = [&]() {
      if (!options.relax_unseen) return 0;
      // A vertex counts as seen when some image sees it within a quarter of an edge.
      const int relaxed = RelaxUnseenVertices(&mesh, VisibleViews(mesh, block, 0.25 * edge_length(level)));
      level_report.relaxed += relaxed;
      UpdateVertexNormals(&mesh);
      return relaxed;
    };
    // After the finest level's adjustment, moves of the vertices with the topology kept
    // (relaxation, hull clamp, untangling, polish) move only the products' surface points.
    auto update_products_surface = [&]() {
      const std::vector<bool> creases =
          DetectCreaseEdges(mesh, adjustment_options.crease_angle_deg, adjustment_options.rounded_ridges);
      UpdateTessellationPoints(BuildPatches(mesh, ComputeCornerNormals(mesh, creases)), &adjusted.tessellation);
    };
    // Walls that stood up during this adjustment stretched their triangles: split them
    // now and adjust again, so a wall carries vertices at the density of roof and
    // ground within the level, not only one level later (issue 7).
    for (int pass = 0; pass < options.wall_passes; ++pass) {
      QualityOptions quality;
      quality.target_edge_length = edge_length(level);
      quality.max_rounds = 1;
      if (CountLongEdges(mesh, quality) == 0) break;
      relax_unseen();
      // Splitting a crumpled wall at G1 midpoints can make triangles cross: then the
      // level keeps its surface without the pass.
      const TinMesh before_split = mesh;
      const int crossing_before = CountSelfIntersections(mesh);
      const QualityReport split = QualityPass(&mesh, quality);
      UpdateVertexNormals(&mesh);
      if (CountSelfIntersections(mesh) > crossing_before) {
        mesh = before_split;
        say("  level " + std::to_string(level) + " wall pass " + std::to_string(pass + 1) +
            ": the splits made triangles cross, pass dropped");
        break;
      }
      say("  level " + std::to_string(level) + " wall pass " + std::to_string(pass + 1) + ": " +
          std::to_string(split.splits) + " splits, " + std::to_string(split.flips) + " flips, " +
          std::to_string(mesh.n_faces()) + " faces; sigma0 before " + std::to_string(adjusted.summary.sigma0));
      adjusted = AdjustLevelInWindows(&mesh, window_images(level), level_options(level), options.windows,
                                      level == finest, options.progress);
      level_report.wall_passes.push_back(
          {split.splits, split.flips, static_cast<int>(mesh.n_faces()), adjusted.summary.sigma0});
    }
    // After vertices moved (normal search, straightening): the level adjusted again, the
    // whole of it (local_rings -1, judged by the level's sigma0) or only the windows
    // within local_rings edge rings of the moved vertices (judged by their own sigma0
    // before and after, engine/local_readjustment.h). done = false: no window to run.
    struct Readjusted {
      LevelAdjustment level;
      double was_sigma0 = 0.0, now_sigma0 = 0.0;
      int local_windows = 0;  // 0: the whole level was adjusted again
      bool done = true;
    };
    auto readjust = [&](const TinMesh& before, int local_rings) {
      Readjusted r;
      r.was_sigma0 = adjusted.summary.sigma0;
      if (local_rings >= 0) {
        LocalReadjustment local = ReadjustAroundMovedVertices(&mesh, before, adjusted, local_rings, window_images(level),
                                                              level_options(level), options.windows, level == finest,
                                                              options.progress);
        r.done = local.windows > 0;
        r.level = std::move(local.level);
        r.was_sigma0 = local.sigma0_before;
        r.now_sigma0 = local.sigma0_after;
        r.local_windows = local.windows;
      } else {
        r.level = AdjustLevelInWindows(&mesh, window_images(level), level_options(level), options.windows,
                                       level == finest, options.progress);
        r.now_sigma0 = r.level.summary.sigma0;
      }
      return r;
    };
    auto lay_wall_corners = [&]() {
      QualityOptions quality;
      quality.target_edge_length = edge_length(level);
      quality.max_rounds = 2;
      if (CountLongEdges(mesh, quality) > 0) {
        // Splits at G1 midpoints barely change the surface, but a crumpled wall can make
        // triangles cross: untangled, or the level keeps its triangles.
        const TinMesh before_split = mesh;
        const int crossing_before = CountSelfIntersections(mesh);
        const QualityReport split = QualityPass(&mesh, quality);
        UpdateVertexNormals(&mesh);
        int crossing_after = CountSelfIntersections(mesh);
        if (crossing_after > crossing_before && options.fold_lips_untangle_rounds > 0) {
          crossing_after = UntangleSelfIntersections(&mesh, options.fold_lips_untangle_rounds).pairs_after;
          UpdateVertexNormals(&mesh);
        }
        if (crossing_after > crossing_before) {
          mesh = before_split;
          say("  level " + std::to_string(level) + " corners: splitting the stretched edges made " +
              std::to_string(crossing_after - crossing_before) + " crossing pairs, left");
        } else {
          level_report.corner_splits = split.splits;
          say("  level " + std::to_string(level) + " corners: " + std::to_string(split.splits) +
              " stretched edges split, " + std::to_string(mesh.n_faces()) + " faces; adjusted again");
          adjusted = AdjustLevelInWindows(&mesh, window_images(level), level_options(level), options.windows,
                                          level == finest, options.progress);
        }
      }
      WallCornerOptions corner_options;
      corner_options.edge_length = edge_length(level);
      corner_options.vertical = options.wall_corners;
      corner_options.feet = options.wall_feet;
      corner_options.eaves = options.wall_eaves;
      corner_options.min_corner_angle_deg = options.wall_corner_min_angle_deg;
      corner_options.merge_wall_pieces = options.wall_merge_pieces;
      if (options.creases_start) options.creases_start(level, mesh);
      WallCornerSearch search = FindWallCorners(mesh, corner_options);
      // Vertical corners first (their bands end half an edge above the foot and below
      // the eave), then feet and eaves.
      std::stable_sort(search.corners.begin(), search.corners.end(),
                       [](const WallCorner& a, const WallCorner& b) { return a.kind < b.kind; });
      level_report.corners_found = search.count(CreaseKind::kVertical);
      level_report.feet_found = search.count(CreaseKind::kFoot);
      level_report.eaves_found = search.count(CreaseKind::kEave);
      say("  level " + std::to_string(level) + " corners: " + std::to_string(search.regions) + " planar regions (" +
          std::to_string(search.wall_regions) + " walls" +
          (search.merged_walls > 0 ? ", " + std::to_string(search.merged_walls) + " wall pieces merged" : std::string()) +
          "), " + std::to_string(level_report.corners_found) +
          " vertical corners" +
          (options.wall_feet ? ", " + std::to_string(level_report.feet_found) + " feet" : std::string()) +
          (options.wall_eaves ? ", " + std::to_string(level_report.eaves_found) + " eaves" : std::string()));
      int crossing = search.corners.empty() ? 0 : CountSelfIntersections(mesh);
      int folded = search.corners.empty() ? 0 : CountFoldedFaces(mesh);
      for (const WallCorner& corner : search.corners) {
        TinMesh before = mesh;
        const CornerLaying laid = LayCornerOntoWalls(&mesh, corner, corner_options);
        if (laid.moved == 0) continue;
        UpdateVertexNormals(&mesh);
        std::ostringstream line;
        line.precision(3);
        line << std::fixed << "  level " << level << ": " << CreaseName(corner.kind) << " at (" << corner.point.x()
             << ", " << corner.point.y() << ", " << corner.point.z() << "), planes " << std::setprecision(1)
             << corner.angle_deg() << std::setprecision(3) << " deg apart, " << laid.moved << " vertices (" << laid.on_line
             << " onto the line), max move " << laid.max_move << " m";
        int crossing_now = CountSelfIntersections(mesh), folded_now = CountFoldedFaces(mesh);
        if ((crossing_now > crossing || folded_now > folded) && options.fold_lips_untangle_rounds > 0) {
          crossing_now = UntangleSelfIntersections(&mesh, options.fold_lips_untangle_rounds).pairs_after;
          UpdateVertexNormals(&mesh);
          folded_now = CountFoldedFaces(mesh);
        }
        if (crossing_now > crossing || folded_now > folded) {
          line << ": " << crossing_now - crossing << " crossing pairs and " << folded_now - folded
               << " folded faces, left";
          say(line.str());
          mesh = std::move(before);
          ++level_report.corners_dropped;
          continue;
        }
        Readjusted re = readjust(before, options.wall_corners_local_rings);
        const bool better = re.done && re.now_sigma0 < re.was_sigma0 * (1.0 + options.wall_corners_tolerance);
        line << "; sigma0 " << re.now_sigma0 << " against " << re.was_sigma0 << " (" << re.local_windows
             << " local windows), " << (better ? "kept" : "dropped");
        say(line.str());
        if (better) {
          adjusted = std::move(re.level);
          ++(corner.kind == CreaseKind::kFoot   ? level_report.feet_laid
             : corner.kind == CreaseKind::kEave ? level_report.eaves_laid
                                                : level_report.corners_laid);
          level_report.corner_vertices_moved += laid.moved;
          crossing = CountSelfIntersections(mesh);
          folded = CountFoldedFaces(mesh);
        } else {
          mesh = std::move(before);
          ++level_report.corners_dropped;
        }
      }
      if (level_report.corners_laid + level_report.feet_laid + level_report.eaves_laid > 0 ||
          level_report.corner_splits > 0)
        update_products_surface();
    };
    // Walls the adjustment left beyond its pull-in: search along the normals again and
    // adjust again, kept only when the level then fits better.
    const int rounds_last_level = cycle > 0 && options.v_cycle_rounds_last_level >= 0
                                      ? options.v_cycle_rounds_last_level
                                      : options.normal_search_rounds_last_level;
    for (int round = 0;
         search_level && round < options.normal_search_rounds && level >= rounds_last_level;
         ++round) {
      TinMesh before = mesh;
      const NormalSearchReport ns = search_normals();
      if (ns.moved == 0) break;
      Readjusted re = readjust(before, options.normal_search_local_rings);
      if (!re.done) break;
      LevelAdjustment& again = re.level;
      const double was_sigma0 = re.was_sigma0, now_sigma0 = re.now_sigma0;
      const int local_windows = re.local_windows;
      const bool better = now_sigma0 < was_sigma0 * (1.0 + options.normal_search_tolerance);
      say("  level " + std::to_string(level) + " normal search round " + std::to_string(round + 1) + ": " +
          std::to_string(ns.moved) + " moved (median " + std::to_string(ns.median_move) + " m); sigma0 " +
          std::to_string(now_sigma0) + " against " + std::to_string(was_sigma0) +
          (local_windows > 0 ? " (" + std::to_string(local_windows) + " local windows)" : "") +
          (better ? ", kept" : ", dropped"));
      if (!better) {
        mesh = std::move(before);
        break;
      }
      adjusted = std::move(again);
      ++level_report.normal_search_rounds;
      level_report.normal_search_local_windows += local_windows;
    }
    // A crease skew to the grid (a zigzag of edges): its vertex chains go onto the
    // crease's line and the level runs again, kept only when it fits better; up to
    // straighten_rounds times while it does (each round refits the line to the
    // surface the last one left). Roof lines and steep lines in rounds of their own
    // (straighten_by_kind): a round of one kind does not fall with the other's.
    const std::vector<std::pair<CreaseLines, std::string>> kinds =
        options.straighten_by_kind
            ? std::vector<std::pair<CreaseLines, std::string>>{{CreaseLines::kRoof, "roof lines"},
                                                                {CreaseLines::kSteep, "steep lines"}}
            : std::vector<std::pair<CreaseLines, std::string>>{{CreaseLines::kAll, ""}};
    for (const auto& [kind, kind_name] : kinds) {
      const std::string what = kind_name.empty() ? "straightening" : "straightening " + kind_name;
      for (int round = 0; round < options.straighten_rounds && !closed; ++round) {
        TinMesh before = mesh;
        const StraightenReport straight = StraightenCreaseChains(
            &mesh, DetectCreaseEdges(mesh, adjustment_options.crease_angle_deg, adjustment_options.rounded_ridges),
            kind);
        if (straight.moved == 0) {
          // Why nothing moved, so that a run's log tells (issue 7: eaves next to crumpled walls).
          if (straight.sets > 0) {
            say("  level " + std::to_string(level) + " " + what + ": " +
                std::to_string(straight.sets) + " crease sets, " + std::to_string(straight.lines) +
                " straight runs, none moved (" + std::to_string(straight.sides_not_planar) +
                " with a side not planar, " + std::to_string(straight.sides_not_meeting) +
                " with sides not meeting on the run, " + std::to_string(straight.too_small + straight.too_short) +
                " too short, " + std::to_string(straight.rejected) + " undone for folds" +
                (kind == CreaseLines::kAll ? "" : ", " + std::to_string(straight.other_kind) + " of the other kind") +
                ")");
          }
          break;
        }
        Readjusted re = readjust(before, options.straighten_local_rings);
        if (!re.done) {
          mesh = std::move(before);
          break;
        }
        LevelAdjustment& again = re.level;
        const double was_sigma0 = re.was_sigma0, now_sigma0 = re.now_sigma0;
        const int local_windows = re.local_windows;
        const bool better = now_sigma0 < was_sigma0 * (1.0 + options.straighten_tolerance);
        say("  level " + std::to_string(level) + " " + what + " " + std::to_string(round + 1) + ": " +
            std::to_string(straight.components) + " straight crease lines, " + std::to_string(straight.moved) +
            " vertices put on them (max " + std::to_string(straight.max_move) + " m, " +
            std::to_string(straight.left_off) + " left off for folds, " +
            std::to_string(straight.flipped) + " faces of no area flipped); sigma0 " +
            std::to_string(now_sigma0) + " against " + std::to_string(was_sigma0) +
            (local_windows > 0 ? " (" + std::to_string(local_windows) + " local windows)" : "") +
            (better ? ", kept" : ", dropped"));
        if (!better) {
          mesh = std::move(before);
          ++level_report.straighten_dropped;
          break;
        }
        adjusted = std::move(again);
        ++level_report.straighten_kept;
        level_report.straightened += straight.moved;
      }
    }
    // Vertical corners of buildings (issue 7): the finest level's last visit splits what
    // the walls stretched, then lays each corner's crumpled band onto its two walls and its
    // line (mesh/wall_corners.h), one corner at a time, kept when the images agree; the
    // same for walls' feet and eaves when asked.
    if ((options.wall_corners || options.wall_feet || options.wall_eaves) && last_pass && !closed && !fitted)
      lay_wall_corners();
    // After the finest level's last adjustment too (a pocket folded under an eave, seen
    // by no image, would stay in the products): same topology, so only the products'
    // surface points move; the grey values there were never observed anyway. Not for
    // closed starts: their rims, seen edge-on, count as unseen (about 200 vertices on the
    // synthetic object), and relaxing them cost its completeness (0.95 -> 0.947).
    const bool relax_now = level > finest || !closed;
    if (relax_now && relax_unseen() > 0 && level == finest) update_products_surface();
    // Lips and pockets beside walls that no image sees (mesh/unseen_lips.h): each laid
    // onto the seen wall's plane, the windows around it adjusted again, kept when the
    // images there agree; one at a time, so that one bad lip does not take the others
    // with it. Closed objects have no walls; a fitted-plane start is a facade itself,
    // its unseen parts are the ground and sky beside it.
    if (options.fold_lips && !closed && !fitted) {
      LipFoldOptions lip_options;
      lip_options.front_tolerance = 0.15 * edge_length(level);
      lip_options.max_plane_rms = 0.25 * edge_length(level);
      const LipSearch search =
          FindUnseenLips(mesh, VisibleViews(mesh, block, 0.25 * edge_length(level)), lip_options);
      if (search.groups > 0) {
        say("  level " + std::to_string(level) + ": " + std::to_string(search.groups) +
            " groups of unseen steep or down-facing vertices, " + std::to_string(search.lips.size()) +
            " lips or pockets off a seen wall (" + std::to_string(search.no_wall) + " without a wall, " +
            std::to_string(search.not_free) + " not free)");
      }
      // "level L: lip at (x, y, z), N vertices" for the log.
      auto describe = [&](const LipFold& fold) {
        std::ostringstream line;
        line.precision(3);
        line << std::fixed << "  level " << level << ": " << (fold.in_front > 0 ? "lip" : "pocket") << " at ("
             << fold.centre.x() << ", " << fold.centre.y() << ", " << fold.centre.z() << "), " << fold.vertices
             << " vertices";
        return line;
      };
      int crossing = search.lips.empty() ? 0 : CountSelfIntersections(mesh);
      int folded = search.lips.empty() ? 0 : CountFoldedFaces(mesh);
      for (const UnseenLip& lip : search.lips) {
        TinMesh before = mesh;
        const LipFold fold = LayLipOntoWall(&mesh, lip, lip_options.embedding_iterations);
        UpdateVertexNormals(&mesh);
        // A lip laid onto a crumpled wall's plane can cut through the wall itself (block A,
        // default, session 27: 89 crossing pairs the untangling could not undo). A few
        // pairs where the laid lip meets its held ring (the far skirt of a shelf in front
        // of block_oblique's leaning wall, session 28) are smoothed out first.
        int crossing_now = CountSelfIntersections(mesh), folded_now = CountFoldedFaces(mesh);
        // Faces folded where the laid sheet meets the held wall: their wall corners within
        // the front tolerance go onto the plane (mesh/unseen_lips.h, FlattenFoldedRim).
        int flattened = 0;
        if (folded_now > folded) {
          flattened = FlattenFoldedRim(&mesh, lip, FoldedFaces(before), lip_options.front_tolerance);
          if (flattened > 0) {
            UpdateVertexNormals(&mesh);
            crossing_now = CountSelfIntersections(mesh);
            folded_now = CountFoldedFaces(mesh);
          }
        }
        const int crossing_laid = crossing_now;
        int untangled = 0;
        // Folds left after the flattening too: the untangling's first round smooths the
        // corners of folded faces (session 29: a 5 m lip on block A's tall building left for 7).
        if ((crossing_now > crossing || folded_now > folded) && options.fold_lips_untangle_rounds > 0) {
          const UntangleReport untangle = UntangleSelfIntersections(&mesh, options.fold_lips_untangle_rounds);
          UpdateVertexNormals(&mesh);
          crossing_now = untangle.pairs_after;
          folded_now = CountFoldedFaces(mesh);
          untangled = untangle.vertices_moved;
        }
        if (crossing_now > crossing || folded_now > folded) {
          std::ostringstream line = describe(fold);
          line << ": laid onto the wall it makes " << crossing_laid - crossing << " crossing pairs";
          if (crossing_now != crossing_laid || untangled > 0) {
            line << " (" << crossing_now - crossing << " after untangling)";
          }
          line << " and " << folded_now - folded << " folded faces"
               << (flattened > 0 ? " (" + std::to_string(flattened) + " wall vertices flattened)" : std::string())
               << ", left";
          say(line.str());
          mesh = std::move(before);
          ++level_report.lips_dropped;
          continue;
        }
        Readjusted re = readjust(before, options.fold_lips_local_rings);
        const bool better = re.done && re.now_sigma0 < re.was_sigma0 * (1.0 + options.fold_lips_tolerance);
        std::ostringstream line = describe(fold);
        line << " (" << fold.in_front << " in front), laid onto the wall (normal " << fold.normal.x()
             << ", " << fold.normal.y() << ", " << fold.normal.z() << "; " << fold.support << " seen vertices, rms "
             << fold.plane_rms << " m), max move " << fold.max_move << " m; sigma0 " << re.now_sigma0
             << " against " << re.was_sigma0 << " (" << re.local_windows << " local windows"
             << (untangled > 0 ? ", " + std::to_string(crossing_laid - crossing) + " crossing pairs untangled, " +
                                     std::to_string(untangled) + " vertices moved"
                               : std::string())
             << (flattened > 0 ? ", " + std::to_string(flattened) + " wall vertices flattened" : std::string())
             << "), "
             << (better ? "kept" : "dropped");
        say(line.str());
        if (better) {
          adjusted = std::move(re.level);
          ++level_report.lips_folded;
          if (untangled > 0) ++level_report.lips_untangled;
          if (flattened > 0) ++level_report.lips_flattened;
          level_report.lip_vertices_moved += fold.vertices;
          crossing = CountSelfIntersections(mesh);
          folded = CountFoldedFaces(mesh);
        } else {
          mesh = std::move(before);
          ++level_report.lips_dropped;
        }
      }
      if (level_report.lips_folded > 0 && level == finest) update_products_surface();
    }
    // Silhouette constraint of a visual-hull start: the surface may not leave the hull.
    if (closed && closed->visual_hull && (options.closed.hull_clamp || options.closed.hull_rims)) {
      const std::vector<bool> creases = DetectCreaseEdges(mesh, adjustment_options.crease_angle_deg,
                                                          adjustment_options.rounded_ridges);
      if (options.closed.hull_clamp) {
        level_report.hull_clamped = ClampToVisualHull(
            *closed, options.closed.hull_clamp_edges * edge_length(level), &mesh, &level_report.hull_unresolved,
            options.closed.clamp_guard);
      }
      if (options.closed.hull_rims) {
        level_report.hull_rim_pushed = PushOntoVisualHullRims(
            *closed, options.closed.hull_rim_edges * edge_length(level), options.closed.hull_rim_cos, &mesh);
      }
      if (level == finest && level_report.hull_clamped + level_report.hull_rim_pushed > 0) {
        // Same topology and the creases of the surface before the clamp: only the
        // products' surface points move.
        UpdateTessellationPoints(BuildPatches(mesh, ComputeCornerNormals(mesh, creases)),
                                 &adjusted.tessellation);
      }
      say("  level " + std::to_string(level) + ": " + std::to_string(level_report.hull_clamped) +
          " vertices pulled inside the visual hull, " + std::to_string(level_report.hull_unresolved) +
          " outside by more than " + std::to_string(options.closed.hull_clamp_edges) + " edges, " +
          std::to_string(level_report.hull_rim_pushed) + " pushed out onto its rims");
    }
    // The untangling counts the crossing pairs it leaves: no second CGAL pass for the report.
    int crossing_left = -1;
    auto untangle = [&]() {
      if (!options.untangle) return;
      const UntangleReport untangled = UntangleSelfIntersections(&mesh);
      crossing_left = untangled.pairs_after;
      if (untangled.rounds == 0) return;
      UpdateVertexNormals(&mesh);
      level_report.crossing_untangled += untangled.pairs_before;
      level_report.untangle_moved += untangled.vertices_moved;
      level_report.untangle_membranes += untangled.membranes;
      if (level == finest) update_products_surface();
      say("  level " + std::to_string(level) + ": " + std::to_string(untangled.pairs_before) +
          " crossing triangle pairs untangled in " + std::to_string(untangled.rounds) + " rounds (" +
          std::to_string(untangled.vertices_moved) + " vertices moved, " +
          (untangled.membranes > 0 ? std::to_string(untangled.membranes) + " membranes, " : "") +
          std::to_string(untangled.pairs_after) + " pairs left" +
          (untangled.kept_best_round ? ", from the round that left the fewest" : "") + ")");
    };
    untangle();
    // The polish (ReconstructionOptions::polish_robust_k): the finest level once more from
    // its finished surface, with robust weights, then relaxed and untangled as above.
    if (level == finest && last_pass && options.polish_robust_k >= 0.0) {
      AdjustmentOptions polish = level_options(level);
      polish.robust_k = options.polish_robust_k;
      polish.reject_k = options.polish_robust_k > 0.0 ? options.polish_reject_k : 0.0;
      level_report.polished = true;
      level_report.sigma0_before_polish = adjusted.summary.sigma0;
      std::ostringstream how;
      how << "stage polish: level " << level << " once more, ";
      if (polish.robust_k > 0.0) {
        how << "Huber weights beyond " << polish.robust_k << " robust sigmas, rejection beyond " << polish.reject_k;
      } else {
        how << "plain least squares";
      }
      say(how.str());
      adjusted = AdjustLevelInWindows(&mesh, window_images(level), polish, options.windows, true, options.progress);
      say("  level " + std::to_string(level) + " polish: sigma0 " + std::to_string(adjusted.summary.sigma0) +
          " (before " + std::to_string(level_report.sigma0_before_polish) + "), " +
          std::to_string(adjusted.summary.rejected) + " observations rejected, " +
          std::to_string(adjusted.summary.downweighted) + " down-weighted");
      if (relax_now) relax_unseen();
      UpdateVertexNormals(&mesh);
      update_products_surface();
      untangle();
    }
    level_report.vertices = static_cast<int>(mesh.n_vertices());
    level_report.faces = static_cast<int>(mesh.n_faces());
    level_report.folded_faces = CountFoldedFaces(mesh);
    level_report.self_intersections = crossing_left >= 0 ? crossing_left : CountSelfIntersections(mesh);
    for (const WindowReport& w : adjusted.windows) {
      for (const IterationReport& it : w.iterations) level_report.fold_limited += it.fold_limited;
    }
    say("  level " + std::to_string(level) + ": " + std::to_string(level_report.folded_faces) +
        " folded faces, " + std::to_string(level_report.self_intersections) + " self-intersecting pairs, " +
        std::to_string(level_report.fold_limited) + " vertex steps limited by the fold guard, " +
        std::to_string(level_report.relaxed) + " unseen vertices relaxed");
    level_report.window = std::move(adjusted.summary);
    level_report.windows = std::move(adjusted.windows);
    level_report.window_core_faces = std::move(adjusted.window_core_faces);
    level_report.window_groups = adjusted.groups;
    if (options.level_done) options.level_done(level, mesh);
    say("  level " + std::to_string(level) + ": " + std::to_string(level_report.windows.size()) +
        " windows in " + std::to_string(level_report.window_groups) + " groups, sigma0 " +
        std::to_string(level_report.window.sigma0));
    for (const auto& it : level_report.windows.size() == 1 ? level_report.window.iterations
                                                            : std::vector<IterationReport>{}) {
      say("  level " + std::to_string(level) + " iteration " + std::to_string(it.iteration) +
          ": sigma0 " + std::to_string(it.sigma0) + ", max dn " + std::to_string(it.max_dn_interior) +
          " m, " + std::to_string(it.observations) + " observations, " +
          std::to_string(it.cg_iterations) + " CG iterations");
    }
    level_report.seconds = Seconds(level_start);
    if (level == finest) {
      result.tessellation = std::move(adjusted.tessellation);
      result.grey = std::move(adjusted.grey);
      result.vertex_sigma = level_report.window.vertex_sigma;
      result.vertex_views = level_report.window.vertex_views;
      result.vertex_flags = level_report.window.vertex_flags;
    }
    result.report.levels.push_back(std::move(level_report));
    if (level == cycle_top && cycle < options.v_cycles) cycle_top_tin = mesh;  // the next cycle starts from it
  }
  result.mesh = std::move(mesh);
  if (options.flatten_crossing_facets) {
    result.report.facet_crossings = FlattenCrossingFacets(result.mesh, &result.tessellation);
    say("surface facets: " + result.report.facet_crossings.Brief());
  }
  result.report.seconds_total = Seconds(start);
  say("done: " + result.report.BriefReport());
  return result;
}

}  // namespace facets
