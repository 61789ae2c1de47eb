#include "apps/reconstruct_command.h"

#include <tbb/global_control.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <ctime>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "engine/pipeline/products.h"
#include "engine/pipeline/reconstruction.h"
#include "io/atomic_file.h"
#include "io/colmap_io.h"
#include "io/ply_io.h"
#include "io/project_io.h"
#include "mesh/closed_surface.h"

namespace facets {
namespace {

// Defaults that depend on the job (docs/EXPERIMENTS.md "Closed objects"): the break-off
// in ground pixels of each level, robust weights for closed objects.
constexpr double kDefaultBreakOffGsd = 0.06;
constexpr double kClosedRobustK = 2.0;
constexpr double kClosedRejectK = 5.0;

struct ReconstructArgs {
  std::string colmap, images, project, out;
  int levels = 3;
  int finest_level = 0;
  double facet_pixels = ReconstructionOptions().facet_pixels;
  double lambda = AdjustmentOptions().lambda;
  std::string regularisation = "curvature";
  // Real photographs need "linear" (docs/EXPERIMENTS.md, fountain); the default stays "none"
  // because the h0/h1 unknowns couple with every unknown of a window and make the
  // block benchmark 2x slower (docs/ENGINE.md, Radiometric model).
  std::string radiometry = "none";
  std::string filter = "binomial5";
  std::string solver = WindowSolverName(AdjustmentOptions().solver);
  std::string sigma_model = AdjustmentOptions().correlated_residuals ? "correlated" : "white";
  std::optional<double> break_off;  // m; none: 0.06 ground pixel of each level
  int max_iterations = AdjustmentOptions().max_iterations;
  double crease_angle = AdjustmentOptions().crease_angle_deg;
  double min_cos_incidence = AdjustmentOptions().min_cos_incidence;
  double min_view_share = AdjustmentOptions().min_view_share;
  bool no_rounded_ridges = false;
  std::optional<double> start_height;
  std::string start = "auto";
  std::string start_plane = "auto";
  int lifting_steps = 0;
  double lifting_range = 30.0;
  std::vector<double> roi;
  std::vector<double> principal_point_shift;  // dx dy in pixels, empty = none
  std::string start_mesh;
  std::string closed_shape = ClosedStartOptions().shape;
  double closed_lifting_range = ClosedStartOptions().lifting_range;
  VisualHullOptions visual_hull;
  bool no_hull_clamp = false;
  bool hull_rims = false;
  bool clamp_guard = false;
  double constraint_voxel = 0.0;
  double hull_rim_cos = ClosedStartOptions().hull_rim_cos;
  double hull_rim_edges = ClosedStartOptions().hull_rim_edges;
  double background_below = AdjustmentOptions().background_below;
  // Silhouette term; the background threshold defaults to the visual hull's.
  double silhouette_weight = AdjustmentOptions().silhouette_weight;
  std::optional<double> silhouette_background;
  std::optional<int> silhouette_open, silhouette_fill_holes;
  double silhouette_rim_cos = AdjustmentOptions().silhouette_rim_cos;
  double silhouette_outside_px = AdjustmentOptions().silhouette_outside_px;
  double silhouette_inside_px = AdjustmentOptions().silhouette_inside_px;
  // None: 2 and 5 for closed starts (pixels past a silhouette see the background),
  // off otherwise.
  std::optional<double> robust, reject;
  std::optional<double> polish;  // ReconstructionOptions::polish_robust_k
  bool colour = false;
  int window_faces = WindowPartitionOptions().max_faces;
  int window_margin = WindowPartitionOptions().margin_rings;
  int sweeps = LevelWindowOptions().sweeps;
  int wall_passes = 0;
  int tangential_smoothing = ReconstructionOptions().tangential_smoothing;
  int straighten_rounds = ReconstructionOptions().straighten_rounds;
  int straighten_local_rings = ReconstructionOptions().straighten_local_rings;
  double straighten_tolerance = ReconstructionOptions().straighten_tolerance;
  bool straighten_by_kind = false;
  bool normal_search_on = false, normal_search_off = false;
  int normal_search_last_level = ReconstructionOptions().normal_search_last_level;
  bool plane_propagation_on = false;
  bool plane_propagation_off = false;
  double start_step_cap = ReconstructionOptions().start_step_cap_pixels;
  int plane_iterations = PlanePropagationOptions().iterations;
  double plane_source_score = PlanePropagationOptions().source_score;
  double plane_max_move = PlanePropagationOptions().max_move_pixels;
  double plane_min_gain = PlanePropagationOptions().min_gain;
  double plane_min_tilt = PlanePropagationOptions().min_target_tilt_deg;
  double plane_slack = PlanePropagationOptions().occluder_slack_pixels;
  int v_cycles = ReconstructionOptions().v_cycles;
  int v_cycle_level = ReconstructionOptions().v_cycle_level;
  double v_cycle_robust = ReconstructionOptions().v_cycle_robust_k;
  int normal_search_rounds = ReconstructionOptions().normal_search_rounds;
  int normal_search_rounds_last_level = ReconstructionOptions().normal_search_rounds_last_level;
  double normal_search_tolerance = ReconstructionOptions().normal_search_tolerance;
  int normal_search_local_rings = ReconstructionOptions().normal_search_local_rings;
  int v_cycle_rounds_last_level = ReconstructionOptions().v_cycle_rounds_last_level;
  bool thorough_walls = false;  // the V-cycle bundle (see --thorough-walls)
  // Every option as given or defaulted, in the form --config reads (settings.ini).
  std::string settings;
  double normal_search_min_cos = NormalSearchOptions().min_cos;
  double normal_search_min_angle = NormalSearchOptions().min_angle_to_views_deg;
  double normal_search_range = NormalSearchOptions().range_pixels;
  double normal_search_min_score = NormalSearchOptions().min_score;
  int normal_search_patch = NormalSearchOptions().patch_half;
  std::string displacement = "normal";
  bool no_fold_guard = false;
  bool no_relax_unseen = false;
  bool no_fold_lips = false;
  bool wall_corners = false;  // set by --wall-corners or the --thorough-walls bundle
  bool wall_feet = false;     // ... --wall-feet
  bool wall_eaves = false;    // ... --wall-eaves
  double wall_corner_min_angle = ReconstructionOptions().wall_corner_min_angle_deg;
  bool no_wall_corners = false;
  bool no_wall_merge = false;
  bool no_untangle = false;
  bool keep_crossing_facets = false;
  bool no_occluders = false;
  bool tiled_images = false;
  double image_memory_mb = 1024.0;
  int threads = 0;
  bool no_glb = false, no_vrml = false, no_rasters = false, no_preview = false, keep_levels = false;
};

void RunReconstruct(const ReconstructArgs& args) {
  const auto start = std::chrono::steady_clock::now();
  std::filesystem::create_directories(args.out);
  std::ostringstream log;
  auto say = [&](const std::string& line) {
    std::cout << line << "\n" << std::flush;
    log << line << "\n";
  };
  std::unique_ptr<tbb::global_control> threads;
  if (args.threads > 0) {
    threads = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                    args.threads);
  }
  if (args.thorough_walls) {
    std::ostringstream bundle;
    bundle << "settings: --thorough-walls: " << args.v_cycles << " v-cycle(s), normal-search rounds in them down to level "
           << args.v_cycle_rounds_last_level << ", tolerance " << args.normal_search_tolerance << ", local rings "
           << args.normal_search_local_rings << ", grey facets of " << args.facet_pixels << " pixels"
           << (args.wall_corners ? ", vertical corners laid onto their walls" : "")
           << (args.wall_feet ? ", walls' feet laid" : "")
           << (args.wall_eaves ? ", eaves laid" : "");
    say(bundle.str());
  }
  ImageBlock block;
  if (!args.project.empty()) {
    say("reading project " + args.project);
    block = ReadProject(args.project);
  } else {
    if (args.colmap.empty() || args.images.empty()) {
      throw std::invalid_argument("give --project FILE, or --colmap SPARSE_DIR and --images IMAGE_DIR");
    }
    say("reading COLMAP model " + args.colmap + " with images in " + args.images);
    block = ReadColmapModel(args.colmap, args.images);
  }
  if (!args.principal_point_shift.empty()) {
    const double dx = args.principal_point_shift[0], dy = args.principal_point_shift[1];
    ShiftPrincipalPoints(block, dx, dy);
    std::ostringstream shift;
    shift << "principal points shifted by (" << dx << ", " << dy << ") pixels";
    say(shift.str());
  }
  say(std::to_string(block.images.size()) + " images, " + std::to_string(block.cameras.size()) +
      " cameras, " + std::to_string(block.points.size()) + " tie points");

  ReconstructionOptions options;
  options.levels = args.levels;
  options.finest_level = args.finest_level;
  options.facet_pixels = args.facet_pixels;
  options.filter = PyramidFilterFromName(args.filter);
  options.adjustment.lambda = args.lambda;
  options.adjustment.regularisation = RegularisationFromName(args.regularisation);
  options.adjustment.radiometry = RadiometricModelFromName(args.radiometry);
  options.adjustment.solver = WindowSolverFromName(args.solver);
  options.adjustment.correlated_residuals = args.sigma_model == "correlated";
  if (args.break_off) {
    options.adjustment.break_off = *args.break_off;
    options.break_off_gsd = 0.0;
  } else {
    options.break_off_gsd = kDefaultBreakOffGsd;
  }
  options.adjustment.max_iterations = args.max_iterations;
  options.adjustment.crease_angle_deg = args.crease_angle;
  options.adjustment.min_cos_incidence = args.min_cos_incidence;
  options.adjustment.min_view_share = args.min_view_share;
  options.adjustment.rounded_ridges = !args.no_rounded_ridges;
  options.start_height = args.start_height;
  // --start closed selects the closed start (engine/start_closed.h); the others are the
  // open starts of engine/start_tiepoints.h.
  options.start_closed = args.start == "closed";
  if (!options.start_closed) options.start = StartSurfaceFromName(args.start);
  if (args.start_plane == "auto") {
    options.start_plane = ReconstructionOptions::StartPlane::kAuto;
  } else if (args.start_plane == "horizontal") {
    options.start_plane = ReconstructionOptions::StartPlane::kHorizontal;
  } else if (args.start_plane == "fitted") {
    options.start_plane = ReconstructionOptions::StartPlane::kFitted;
  } else {
    throw std::invalid_argument("--start-plane must be auto, horizontal or fitted, not '" + args.start_plane + "'");
  }
  options.lifting_steps = args.lifting_steps;
  options.lifting_range = args.lifting_range;
  options.colour = args.colour;
  options.closed.mesh_file = args.start_mesh;
  options.closed.shape = args.closed_shape;
  options.closed.lifting_steps = args.lifting_steps;
  options.closed.lifting_range = args.closed_lifting_range;
  options.closed.visual_hull = args.visual_hull;
  options.closed.hull_clamp = !args.no_hull_clamp;
  options.closed.hull_rims = args.hull_rims;
  options.closed.clamp_guard = args.clamp_guard;
  options.closed.constraint_voxel = args.constraint_voxel;
  options.closed.hull_rim_cos = args.hull_rim_cos;
  options.closed.hull_rim_edges = args.hull_rim_edges;
  options.closed.write_start = (std::filesystem::path(args.out) / "start.ply").string();
  options.adjustment.background_below = args.background_below;
  options.adjustment.silhouette_weight = args.silhouette_weight;
  options.adjustment.silhouette_rim_cos = args.silhouette_rim_cos;
  options.adjustment.silhouette_outside_px = args.silhouette_outside_px;
  options.adjustment.silhouette_inside_px = args.silhouette_inside_px;
  options.silhouette_foreground = args.visual_hull.foreground;
  if (args.silhouette_background) options.silhouette_foreground.background_max = *args.silhouette_background;
  if (args.silhouette_open) options.silhouette_foreground.open_radius = *args.silhouette_open;
  if (args.silhouette_fill_holes) options.silhouette_foreground.fill_holes_below = *args.silhouette_fill_holes;
  const bool closed = options.start_closed || !args.start_mesh.empty();
  options.adjustment.robust_k = args.robust.value_or(closed ? kClosedRobustK : 0.0);
  options.adjustment.reject_k = args.reject.value_or(closed ? kClosedRejectK : 0.0);
  options.windows.partition.max_faces = args.window_faces;
  options.windows.partition.margin_rings = args.window_margin;
  options.windows.sweeps = args.sweeps;
  options.tangential_smoothing = args.tangential_smoothing;
  options.straighten_rounds = args.straighten_rounds;
  options.straighten_local_rings = args.straighten_local_rings;
  options.straighten_tolerance = args.straighten_tolerance;
  if (args.normal_search_on) options.normal_search = true;
  if (args.normal_search_off) options.normal_search = false;
  options.normal_search_last_level = args.normal_search_last_level;
  if (args.plane_propagation_on) options.plane_propagation = true;
  if (args.plane_propagation_off) options.plane_propagation = false;
  options.start_step_cap_pixels = args.start_step_cap;
  options.plane_propagation_options.iterations = args.plane_iterations;
  options.plane_propagation_options.source_score = args.plane_source_score;
  options.plane_propagation_options.max_move_pixels = args.plane_max_move;
  options.plane_propagation_options.min_gain = args.plane_min_gain;
  options.plane_propagation_options.min_target_tilt_deg = args.plane_min_tilt;
  options.plane_propagation_options.occluder_slack_pixels = args.plane_slack;
  options.v_cycles = args.v_cycles;
  options.v_cycle_level = args.v_cycle_level;
  options.v_cycle_robust_k = args.v_cycle_robust;
  options.normal_search_rounds = args.normal_search_rounds;
  options.normal_search_rounds_last_level = args.normal_search_rounds_last_level;
  options.normal_search_tolerance = args.normal_search_tolerance;
  options.normal_search_local_rings = args.normal_search_local_rings;
  options.v_cycle_rounds_last_level = args.v_cycle_rounds_last_level;
  options.normal_search_options.min_cos = args.normal_search_min_cos;
  options.normal_search_options.min_angle_to_views_deg = args.normal_search_min_angle;
  options.normal_search_options.range_pixels = args.normal_search_range;
  options.normal_search_options.min_score = args.normal_search_min_score;
  options.normal_search_options.patch_half = args.normal_search_patch;
  options.adjustment.displacement = DisplacementFromName(args.displacement);
  options.adjustment.fold_guard = !args.no_fold_guard;
  options.relax_unseen = !args.no_relax_unseen;
  options.fold_lips = !args.no_fold_lips;
  // --no-wall-corners excludes the three flags and keeps --thorough-walls from setting them.
  options.wall_corners = args.wall_corners;
  options.wall_feet = args.wall_feet;
  options.wall_eaves = args.wall_eaves;
  options.wall_corner_min_angle_deg = args.wall_corner_min_angle;
  options.wall_merge_pieces = !args.no_wall_merge;
  options.untangle = !args.no_untangle;
  options.flatten_crossing_facets = !args.keep_crossing_facets;
  options.windows.occluders = !args.no_occluders;
  // Level images in memory while they fit the budget, else tiled on disk and read per
  // window (pyramid: 4/3 of the finest kept level; float per channel).
  double pyramid_mb = 0.0;
  for (const auto& image : block.images) {
    const Camera& camera = block.CameraOf(image);
    // Levels from --finest-level up: 4/3 of that level's pixels.
    pyramid_mb += 4.0 / 3.0 * std::pow(0.25, args.finest_level) * camera.width * camera.height *
                  (args.colour ? 3 : 1) * 4.0 / (1024.0 * 1024.0);
  }
  if (args.tiled_images || pyramid_mb > args.image_memory_mb) {
    options.image_cache_dir = (std::filesystem::path(args.out) / ".image-cache").string();
    options.image_cache_mb = std::max(64.0, 0.5 * args.image_memory_mb);
    say("level images: " + std::to_string(static_cast<int>(pyramid_mb)) + " MB, read per window from tiled files");
  }
  if (!args.roi.empty()) {
    if (args.roi.size() != 6) throw std::invalid_argument("--roi takes 6 numbers: xmin ymin zmin xmax ymax zmax");
    RegionOfInterest roi;
    roi.min = Eigen::Vector3d(args.roi[0], args.roi[1], args.roi[2]) - block.origin;
    roi.max = Eigen::Vector3d(args.roi[3], args.roi[4], args.roi[5]) - block.origin;
    options.roi = roi;
  }
  options.progress = say;
  if (args.keep_levels) {
    const std::filesystem::path dir = std::filesystem::path(args.out) / "levels";
    std::filesystem::create_directories(dir);
    auto keep = [dir](const std::string& name, const TinMesh& mesh) {
      const std::string path = (dir / name).string();
      WritePly(path + ".tmp", TinGeometryData(mesh));
      CommitTemporary(path + ".tmp", path);
    };
    options.level_done = [keep](int level, const TinMesh& mesh) {
      keep("level_" + std::to_string(level) + ".ply", mesh);
    };
    // The TIN the corner step starts from, to replay that step without images.
    options.creases_start = [keep](int level, const TinMesh& mesh) {
      keep("level_" + std::to_string(level) + "_creases.ply", mesh);
    };
  }
  const Reconstruction result = Reconstruct(block, options);

  // Products: each written to a temporary name and renamed (io/atomic_file.h).
  say("stage products: writing into " + args.out);
  ProductOptions products;
  products.glb = !args.no_glb;
  products.vrml = !args.no_vrml;
  products.ortho = products.dsm = products.sigma = !args.no_rasters;
  products.preview = !args.no_preview;
  const std::vector<std::string> files = WriteProducts(result, block, args.out, products);
  std::string list;
  for (const auto& f : files) list += " " + f;
  say("  written:" + list);
  const std::filesystem::path out(args.out);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (options.start_closed || !options.closed.mesh_file.empty()) {
    // A closed start must come out closed and without self-intersections.
    say("closed surface: TIN " + CheckClosedSurface(result.mesh).Brief() + "; surface facets " +
        CheckClosedSurface(result.tessellation.points, result.tessellation.triangles).Brief());
  }
  const WindowReport& finest = result.report.levels.back().window;
  if (finest.background > 0 || finest.rejected > 0 || finest.downweighted > 0) {
    const double all = static_cast<double>(std::max<long long>(finest.observations + finest.rejected, 1));
    say("finest level: " + std::to_string(finest.background) + " background pixels dropped, " +
        std::to_string(finest.rejected) + " observations rejected (" +
        std::to_string(100.0 * finest.rejected / all) + " %), " + std::to_string(finest.downweighted) +
        " down-weighted (" + std::to_string(100.0 * finest.downweighted / all) + " %)");
  }
  int flagged = 0;
  for (uint8_t f : result.vertex_flags) flagged += f != 0 ? 1 : 0;
  say("summary: " + std::to_string(result.mesh.n_vertices()) + " vertices (" + std::to_string(flagged) +
      " flagged), " + std::to_string(result.tessellation.triangles.size()) + " surface facets, sigma0 " +
      std::to_string(result.report.levels.back().window.sigma0) + " grey values, " +
      std::to_string(seconds) + " s; products in " + args.out);
  if (!args.settings.empty()) WriteFileAtomically((out / "settings.ini").string(), args.settings);
  WriteFileAtomically((out / "facets.log").string(), log.str());
}

// Every option of the run in the form --config reads: a [reconstruct] section with the
// options as given or defaulted, less those without a value (empty strings, flags not
// set: the defaults anyway); `effective` replaces the values of options a bundle set.
std::string SettingsFile(const CLI::App& sub, const std::map<std::string, std::string>& effective) {
  std::istringstream lines(sub.config_to_str(true, false));
  std::ostringstream file;
  file << "# every option of a facets reconstruct run: facets reconstruct --config settings.ini --out OTHER\n"
       << "[reconstruct]\n";
  std::string line;
  while (std::getline(lines, line)) {
    if (line.empty() || line.front() == '[') continue;
    const size_t eq = line.find('=');
    if (eq == std::string::npos) continue;
    const std::string key = line.substr(0, eq);
    const auto set = effective.find(key);
    const std::string value = set != effective.end() ? set->second : line.substr(eq + 1);
    if (value == "\"\"" || value == "false") continue;
    file << key << "=" << value << "\n";
  }
  return file.str();
}

}  // namespace

void AddReconstructCommand(CLI::App& app) {
  auto args = std::make_shared<ReconstructArgs>();
  CLI::App* sub = app.add_subcommand("reconstruct", "reconstruct the surface from oriented images (--config FILE: options from a "
                                                    "settings.ini as each run writes; the command line wins)");
  // `facets reconstruct --config FILE`: the option belongs to the top-level app (see
  // apps/facets_main.cc) and falls through to it.
  sub->fallthrough();
  sub->add_option("--colmap", args->colmap, "COLMAP text model folder (cameras.txt, images.txt)");
  sub->add_option("--images", args->images, "image folder of the COLMAP model");
  sub->add_option("--project", args->project, "native project file (JSON)");
  sub->add_option("--out", args->out, "output folder")->required();
  sub->add_option("--levels", args->levels, "image pyramid levels (1 = no pyramid)")->capture_default_str();
  sub->add_option("--finest-level", args->finest_level,
                  "last adjusted pyramid level (0 = the original images; K: products at 2^K times their "
                  "ground pixel, levels levels-1..K adjusted)")
      ->capture_default_str();
  sub->add_option("--facet-pixels", args->facet_pixels,
                  "edge of a grey facet in pixels of each level (a triangle edge is 4 facets)")
      ->capture_default_str();
  sub->add_option("--lambda", args->lambda, "regularisation weight (docs/ENGINE.md)")->capture_default_str();
  sub->add_option("--regularisation", args->regularisation, "curvature | adaptive | none")->capture_default_str();
  sub->add_option("--radiometry", args->radiometry, "none | constant | linear")->capture_default_str();
  sub->add_option("--filter", args->filter, "pyramid filter: binomial3 | binomial5 | meer13")->capture_default_str();
  sub->add_option("--sigma-model", args->sigma_model,
                  "vertex sigma: white (residuals independent) | correlated (variance factor from the residuals' "
                  "correlation between neighbouring pixels, docs/ENGINE.md)")
      ->check(CLI::IsMember({"white", "correlated"}))
      ->capture_default_str();
  sub->add_option("--solver", args->solver,
                  "window solver: ldlt (sparse LDL^T, pattern analysed once per window) | pcg (SSOR-PCG)")
      ->check(CLI::IsMember({"ldlt", "pcg"}))
      ->capture_default_str();
  sub->add_option("--break-off", args->break_off, "largest displacement at the finest level (m); default 0.06 ground pixel of each level");
  sub->add_option("--max-iterations", args->max_iterations, "per level")->capture_default_str();
  sub->add_option("--crease-angle", args->crease_angle, "crease detection angle (deg); 180 = pure G1")->capture_default_str();
  sub->add_option("--min-view-share", args->min_view_share,
                  "an image is a view of a vertex with at least this share of the best image's pixels on its faces "
                  "(fewer than 2 views: flagged, creases regularised)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1.0));
  sub->add_option("--min-cos-incidence", args->min_cos_incidence,
                  "rays meeting a facet at |cos| below this (more grazing) are no observation")
      ->capture_default_str();
  sub->add_flag("--no-rounded-ridges", args->no_rounded_ridges,
                "creases only where one edge bends by the crease angle, not the middle of a rounded band (always so for closed starts)");
  sub->add_option("--start-height", args->start_height, "height of the start plane (local Z)");
  sub->add_option("--start", args->start,
                  "start surface: auto | plane | tiepoints | closed (auto: tie points when >= 20 lie in "
                  "the region and neither --start-height nor lifting is given; closed: an ellipsoid "
                  "or hull around the tie points, for objects)")
      ->check(CLI::IsMember({"auto", "plane", "tiepoints", "closed"}))
      ->capture_default_str();
  sub->add_option("--start-plane", args->start_plane,
                  "auto (fitted to the tie points when tilted > 45 deg, e.g. a facade) | horizontal | fitted")
      ->capture_default_str();
  sub->add_option("--lifting-steps", args->lifting_steps, "object lifting: start heights to try (0 = off)")->capture_default_str();
  sub->add_option("--lifting-range", args->lifting_range, "object lifting: search interval (m)")->capture_default_str();
  sub->add_option("--roi", args->roi, "region of interest: xmin ymin zmin xmax ymax zmax (global)")->expected(6);
  sub->add_option("--principal-point-shift", args->principal_point_shift,
                  "add DX DY pixels to every camera's principal point: a calibration whose top-left "
                  "pixel centre is (0, 0) (e.g. Middlebury's K matrices) needs 0.5 0.5")
      ->expected(2);
  sub->add_option("--start-mesh", args->start_mesh, "closed (or any) start mesh, PLY or OBJ, local coordinates");
  sub->add_option("--closed-shape", args->closed_shape,
                  "automatic closed start: ellipsoid | hull (convex hull of the tie points) | visual-hull (carved to the silhouettes)")->capture_default_str();
  sub->add_option("--hull-background", args->visual_hull.foreground.background_max,
                  "visual-hull start: grey values <= this are background")->capture_default_str();
  sub->add_option("--hull-voxel", args->visual_hull.voxel_size,
                  "visual-hull start: voxel edge (m; 0 = the box's longest side / 200)")->capture_default_str();
  sub->add_option("--hull-misses", args->visual_hull.allowed_misses,
                  "visual-hull start: images that may see background at a kept voxel")->capture_default_str();
  sub->add_flag("--no-hull-clamp", args->no_hull_clamp,
                "visual-hull start: let the surface leave the hull (no silhouette constraint)");
  sub->add_option("--hull-constraint-voxel", args->constraint_voxel,
                  "visual-hull start: voxel edge of the hull the surface is held to after each level "
                  "(m; 0 = the start's hull)")->capture_default_str();
  sub->add_option("--hull-rim-cos", args->hull_rim_cos,
                  "visual-hull start: a vertex is on a rim where |normal . ray| <= this")->capture_default_str();
  sub->add_option("--hull-rim-edges", args->hull_rim_edges,
                  "visual-hull start: farthest push onto a rim, in edge lengths")->capture_default_str();
  sub->add_flag("--hull-clamp-guard", args->clamp_guard,
                "visual-hull start: halve, at last undo, pulls inside the hull that fold or cross faces");
  sub->add_flag("--hull-rims", args->hull_rims,
                "visual-hull start: push the surface out onto the hull's rims after each level");
  sub->add_option("--closed-lifting-range", args->closed_lifting_range,
                  "object lifting of a closed start: scale factors over 1 +- range/2")->capture_default_str();
  sub->add_option("--silhouette-weight", args->silhouette_weight,
                  "silhouette term: weight of a rim vertex's distance to the image outline "
                  "(grey values^2 per level pixel^2; 0 = off; objects before a dark background)")->capture_default_str();
  sub->add_option("--silhouette-background", args->silhouette_background,
                  "silhouette term: grey values <= this are background (default: --hull-background)");
  sub->add_option("--silhouette-open", args->silhouette_open,
                  "silhouette term: opening radius of the foreground mask (pixels; default: the visual hull's, 1)");
  sub->add_option("--silhouette-fill-holes", args->silhouette_fill_holes,
                  "silhouette term: enclosed background holes under this many pixels are foreground "
                  "(default: the visual hull's, 500)");
  sub->add_option("--silhouette-rim-cos", args->silhouette_rim_cos,
                  "silhouette term: a vertex is on an image's rim where |normal . ray| <= this")->capture_default_str();
  sub->add_option("--silhouette-outside-px", args->silhouette_outside_px,
                  "silhouette term: farthest rim projection onto background used (level pixels)")->capture_default_str();
  sub->add_option("--silhouette-inside-px", args->silhouette_inside_px,
                  "silhouette term: farthest rim projection inside the outline used (level pixels)")->capture_default_str();
  sub->add_option("--background-below", args->background_below,
                  "pixels with grey value at or below this are background, no observation (negative = off)")->capture_default_str();
  sub->add_option("--robust", args->robust, "Huber weights beyond K robust sigmas (0 = off; default 2 for closed starts, else off)");
  sub->add_option("--reject", args->reject, "reject residuals beyond R robust sigmas (0 = off; default 5 for closed starts, else off)");
  sub->add_flag("--colour", args->colour, "one grey value per channel (geometry shared)");
  sub->add_option("--window-faces", args->window_faces, "most core triangles per window")->capture_default_str();
  sub->add_option("--window-margin", args->window_margin, "face rings around a window's core")->capture_default_str();
  sub->add_option("--sweeps", args->sweeps, "sweeps over the windows of a level")->capture_default_str();
  sub->add_option("--wall-passes", args->wall_passes,
                  "per level: split edges walls stretched and adjust again, at most this often")
      ->capture_default_str()
      ->check(CLI::Range(0, 10));
  sub->add_option("--tangential-smoothing", args->tangential_smoothing,
                  "per finer level: iterations of tangential smoothing on the creased G1 surface (0 = off)")
      ->capture_default_str()
      ->check(CLI::Range(0, 10));
  sub->add_option("--straighten-rounds", args->straighten_rounds,
                  "per level: put straight crease chains on their line and adjust again, kept while sigma0 "
                  "does not rise (--straighten-tolerance), at most this often (0 = off)")
      ->capture_default_str()
      ->check(CLI::Range(0, 10));
  sub->add_option("--straighten-local-rings", args->straighten_local_rings,
                  "straightening: adjust again only the windows over the faces within this many edge rings of "
                  "the vertices it moved, judged by those windows' sigma0 (-1 = the whole level)")
      ->capture_default_str()
      ->check(CLI::Range(-1, 50));
  sub->add_option("--straighten-tolerance", args->straighten_tolerance,
                  "straightening: kept unless sigma0 rises by more than this share (0 = only when it drops)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1.0));
  sub->add_flag("--straighten-by-kind", args->straighten_by_kind,
                "straightening: roof lines (ridges, hips) and then steep lines (eaves, feet) in rounds of their own, "
                "each kept or dropped by itself (default: one round of all lines)");
  sub->add_flag("--normal-search", args->normal_search_on,
                "before each finer level: steep vertices (walls) search along their normals for the offset where the "
                "images agree best, so walls a coarser level left several pixels off come back (default: on for "
                "plane and tie-point starts, off for closed and facade starts)");
  sub->add_flag("--no-normal-search", args->normal_search_off, "no normal search")
      ->excludes("--normal-search");
  sub->add_option("--normal-search-last-level", args->normal_search_last_level,
                  "normal search: finest pyramid level searched")
      ->capture_default_str()
      ->check(CLI::Range(0, 20));
  sub->add_option("--v-cycles", args->v_cycles,
                  "after the finest level: go back up to --v-cycle-level (its TIN put onto the finished surface) "
                  "and adjust down again, this often (0 = off; each costs those levels again)")
      ->capture_default_str()
      ->check(CLI::Range(0, 10));
  sub->add_option("--v-cycle-level", args->v_cycle_level, "v-cycles: the pyramid level to go back up to")
      ->capture_default_str()
      ->check(CLI::Range(1, 20));
  sub->add_option("--v-cycle-rounds-last-level", args->v_cycle_rounds_last_level,
                  "v-cycles: finest pyramid level with normal search rounds in the cycles (-1 = as "
                  "--normal-search-rounds-last-level)")
      ->capture_default_str()
      ->check(CLI::Range(-1, 20));
  sub->add_option("--v-cycle-robust", args->v_cycle_robust,
                  "v-cycles: Huber weights beyond K robust sigmas and rejection beyond 5 on their levels (0 = plain "
                  "least squares)")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  sub->add_flag("--plane-propagation", args->plane_propagation_on,
                "after each normal search: vertices try the planes of neighbours whose images agree there "
                "(PatchMatch-like, a ring further per iteration; default: on wherever the normal search runs)");
  sub->add_flag("--no-plane-propagation", args->plane_propagation_off, "no plane propagation")
      ->excludes("--plane-propagation");
  sub->add_option("--plane-iterations", args->plane_iterations, "plane propagation: iterations")
      ->capture_default_str()
      ->check(CLI::Range(1, 50));
  sub->add_option("--plane-source-score", args->plane_source_score,
                  "plane propagation: vertices lend their plane at this mean pairwise correlation or more, and "
                  "borrow below it")
      ->capture_default_str()
      ->check(CLI::Range(-1.0, 1.0));
  sub->add_option("--plane-min-gain", args->plane_min_gain,
                  "plane propagation: a borrowed plane must score this much above the vertex's own patch")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 2.0));
  sub->add_option("--plane-min-tilt", args->plane_min_tilt,
                  "plane propagation: only vertices whose normal turns at least this far (deg) from vertical borrow "
                  "(0 = every vertex)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 90.0));
  sub->add_option("--plane-occluder-slack", args->plane_slack,
                  "plane propagation: a borrowed plane counts an image as seeing it when no surface lies in the way "
                  "nearer than this many level pixels (at least the move)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 64.0));
  sub->add_option("--start-step-cap", args->start_step_cap,
                  "tie-point start: after the coarsest level, nodes at most this many of its pixels from their "
                  "tie-point heights (0 = off)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 64.0));
  sub->add_option("--plane-max-move", args->plane_max_move,
                  "plane propagation: a vertex moves onto a plane at most this many level pixels away")
      ->capture_default_str()
      ->check(CLI::Range(0.5, 64.0));
  sub->add_option("--polish", args->polish,
                  "after the finest level: adjust it once more from its finished surface, with Huber weights beyond K "
                  "robust sigmas and rejection beyond 5 (0 = plain least squares; off by default: it costs as much "
                  "as the finest level again)")
      ->check(CLI::NonNegativeNumber);
  sub->add_option("--normal-search-rounds", args->normal_search_rounds,
                  "normal search: after a level's adjustment search and adjust again, kept while sigma0 drops, "
                  "at most this often")
      ->capture_default_str()
      ->check(CLI::Range(0, 10));
  sub->add_option("--normal-search-min-cos", args->normal_search_min_cos,
                  "normal search: an image is used where it sees the vertex's tangent plane at |cos| >= this")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1.0));
  sub->add_option("--normal-search-rounds-last-level", args->normal_search_rounds_last_level,
                  "normal search: finest pyramid level with rounds")
      ->capture_default_str()
      ->check(CLI::Range(0, 20));
  sub->add_option("--normal-search-tolerance", args->normal_search_tolerance,
                  "normal search: a round is kept when sigma0 stays below (1 + this) x sigma0 before it (0 = only "
                  "when it drops)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1.0));
  sub->add_option("--normal-search-local-rings", args->normal_search_local_rings,
                  "normal search: rounds re-adjust only windows over the faces within this many edge rings of "
                  "the vertices that moved, judged by those windows' sigma0 (-1 = the whole level)")
      ->capture_default_str()
      ->check(CLI::Range(-1, 50));
  sub->add_option("--normal-search-min-angle", args->normal_search_min_angle,
                  "normal search: only vertices whose normal turns more than this (deg) from the mean direction to "
                  "the images that see them (0 = all; 45: walls of an aerial block)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 90.0));
  sub->add_option("--normal-search-patch", args->normal_search_patch,
                  "normal search: patch of (2 N + 1)^2 samples one level pixel apart")
      ->capture_default_str()
      ->check(CLI::Range(1, 16));
  sub->add_option("--normal-search-range", args->normal_search_range,
                  "normal search: offsets over +- this many level pixels")
      ->capture_default_str()
      ->check(CLI::Range(1.0, 64.0));
  sub->add_option("--normal-search-min-score", args->normal_search_min_score,
                  "normal search: least mean pairwise correlation of a peak")
      ->capture_default_str()
      ->check(CLI::Range(-1.0, 1.0));
  sub->add_option("--displacement", args->displacement,
                  "normal (3D: walls stand up) | vertical (2.5D, for comparison)")
      ->capture_default_str();
  sub->add_flag("--no-relax-unseen", args->no_relax_unseen,
                "leave vertices no image saw where the adjustment left them");
  sub->add_flag("--no-fold-lips", args->no_fold_lips,
                "leave lips in front of walls whose underside no image sees, and pockets behind them, where the "
                "adjustment left them (by default they are laid onto the seen wall's plane and kept when the "
                "images agree)");
  sub->add_flag("--no-untangle", args->no_untangle,
                "leave triangle pairs that cross after a level as they are (they are counted in report.json)");
  sub->add_flag("--keep-crossing-facets", args->keep_crossing_facets,
                "write the surface facets as adjusted even where they cross (by default their "
                "patches are pulled toward the TIN's chords there; counted in report.json)");
  sub->add_flag("--no-fold-guard", args->no_fold_guard, "do not limit vertex steps that would fold the surface");
  sub->add_flag("--no-occluders", args->no_occluders, "windows do not see the surface around them");
  sub->add_flag("--tiled-images", args->tiled_images, "level images on disk, read per window (also when over --image-memory)");
  sub->add_option("--image-memory", args->image_memory_mb, "MB for level images in memory; more goes to tiled files")->capture_default_str();
  sub->add_option("--threads", args->threads, "threads (0 = all cores)")->capture_default_str();
  sub->add_flag("--no-glb", args->no_glb, "do not write surface.glb");
  sub->add_flag("--no-vrml", args->no_vrml, "do not write surface.wrl");
  sub->add_flag("--no-rasters", args->no_rasters, "do not write ortho.tif, dsm.tif, sigma.tif");
  sub->add_flag("--no-preview", args->no_preview, "do not write preview.png");
  sub->add_flag("--keep-levels", args->keep_levels,
                "also write each level's TIN as levels/level_K.ply (K = pyramid level), and the TIN the "
                "corner step starts from as levels/level_K_creases.ply");
  auto* corners_on = sub->add_flag(
      "--wall-corners", args->wall_corners,
      "finest level: split the edges walls stretched, then lay each vertical corner's band onto its two walls and "
      "their line, kept when the images agree (on with --thorough-walls)");
  auto* feet_on = sub->add_flag("--wall-feet", args->wall_feet,
                                "finest level: lay the crease where a wall meets the ground (or a lower roof) "
                                "onto both, like --wall-corners (on with --thorough-walls)");
  auto* eaves_on = sub->add_flag("--wall-eaves", args->wall_eaves,
                                 "finest level: lay the crease where a wall meets its roof onto both, like "
                                 "--wall-corners (on with --thorough-walls)");
  sub->add_option("--wall-corner-min-angle", args->wall_corner_min_angle,
                  "least angle in degrees between two walls' normals for a vertical corner (45..90)")
      ->capture_default_str();
  sub->add_flag("--no-wall-merge", args->no_wall_merge,
                "corner step: keep the planar wall pieces apart instead of merging those within an edge of each "
                "other that one plane fits");
  sub->add_flag("--no-wall-corners", args->no_wall_corners,
                "no corner, foot or eave laying, also with --thorough-walls")
      ->excludes(corners_on)
      ->excludes(feet_on)
      ->excludes(eaves_on);
  sub->add_flag("--thorough-walls", args->thorough_walls,
                "walls (issue 7): 1.5-pixel facets and one V-cycle with normal-search rounds down to level 0, "
                "re-adjusted locally (--facet-pixels 1.5 --v-cycles 1 --v-cycle-rounds-last-level 0 "
                "--normal-search-tolerance 1 --normal-search-local-rings 1 --wall-corners --wall-feet --wall-eaves, each "
                "unless given); about 7x the time");
  sub->callback([args, sub] {
    try {
      std::map<std::string, std::string> bundled;  // option -> value the bundle set
      if (args->thorough_walls) {
        // The bundle set by hand before: options the user gives explicitly win.
        auto bundle = [&](const std::string& name, const std::string& value, auto* field, auto setting) {
          if (sub->count("--" + name) > 0) return;
          *field = setting;
          bundled[name] = value;
        };
        bundle("v-cycles", "1", &args->v_cycles, 1);
        bundle("v-cycle-rounds-last-level", "0", &args->v_cycle_rounds_last_level, 0);
        bundle("normal-search-tolerance", "1", &args->normal_search_tolerance, 1.0);
        bundle("normal-search-local-rings", "1", &args->normal_search_local_rings, 1);
        bundle("facet-pixels", "1.5", &args->facet_pixels, 1.5);
        if (!args->no_wall_corners) {
          bundle("wall-corners", "true", &args->wall_corners, true);
          bundle("wall-feet", "true", &args->wall_feet, true);
          bundle("wall-eaves", "true", &args->wall_eaves, true);
        }
      }
      args->settings = SettingsFile(*sub, bundled);
      RunReconstruct(*args);
    } catch (const std::exception& e) {
      std::cerr << "facets reconstruct: error: " << e.what() << "\n";
      throw CLI::RuntimeError(1);
    }
  });
}

}  // namespace facets
