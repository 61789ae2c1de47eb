#include "apps/reconstruct_expert_options.h"

#include <string>

namespace facets {
namespace {

// The window adjustment's estimator (engine/solver/adjustment_options.h).
void BindAdjustment(const OptionBinder& bind, ReconstructionOptions& options) {
  AdjustmentOptions& adjustment = options.adjustment;
  bind.Choice("--regularisation", adjustment.regularisation,
              {{"curvature", Regularisation::kCurvature},
               {"adaptive", Regularisation::kAdaptive},
               {"none", Regularisation::kNone}},
              "pseudo-observations per vertex: curvature = 0, curvature re-estimated from the images, or none");
  bind.Choice("--filter", options.filter,
              {{"binomial3", PyramidFilter::kBinomial3},
               {"binomial5", PyramidFilter::kBinomial5},
               {"meer13", PyramidFilter::kMeer13}},
              "image pyramid filter");
  bind.Choice("--sigma-model", adjustment.correlated_residuals, {{"white", false}, {"correlated", true}},
              "vertex sigma: residuals independent (white) or the variance factor from their correlation between "
              "neighbouring pixels (correlated, docs/ENGINE.md)");
  bind.Choice("--solver", adjustment.solver, {{"ldlt", WindowSolver::kLdlt}, {"pcg", WindowSolver::kPcg}},
              "window solver: sparse LDL^T (pattern analysed once per window) or SSOR-PCG");
  bind.Choice("--displacement", adjustment.displacement,
              {{"normal", Displacement::kNormal}, {"vertical", Displacement::kVertical}},
              "vertices move along their normals (3D: walls stand up) or vertically (2.5D, for comparison)");
  bind.Value("--break-off-gsd", options.break_off_gsd,
             "the iteration stops when the largest displacement falls below this many ground pixels of the level "
             "(0: --break-off in m)")
      ->check(CLI::NonNegativeNumber);
  bind.Function<double>(
          "--break-off",
          [&options](const double& metres) {
            options.adjustment.break_off = metres;
            options.break_off_gsd = 0.0;
          },
          [&options] { return options.break_off_gsd > 0.0 ? std::string() : ConfigText(options.adjustment.break_off); },
          "break-off in m at the finest level, doubled per coarser level, instead of --break-off-gsd")
      ->check(CLI::PositiveNumber);
  bind.Value("--crease-angle", adjustment.crease_angle_deg,
             "edges whose faces' normals differ by more (deg) are creases; 180 = a G1 surface everywhere");
  bind.Value("--min-view-share", adjustment.min_view_share,
             "an image is a view of a vertex with at least this share of the best image's pixels on its faces "
             "(fewer than 2 views: flagged, creases regularised)")
      ->check(CLI::Range(0.0, 1.0));
  bind.Value("--min-cos-incidence", adjustment.min_cos_incidence,
             "rays meeting a facet at |cos| below this (more grazing) are no observation");
  bind.Negative("--no-rounded-ridges", adjustment.rounded_ridges,
                "creases only where one edge bends by the crease angle, not the middle of a rounded band");
  bind.Value("--background-below", adjustment.background_below,
             "pixels with a grey value at or below this are background, no observation (negative = off)");
  bind.Value("--robust", adjustment.robust_k, "Huber weights beyond K robust sigmas (0 = off)")
      ->check(CLI::NonNegativeNumber);
  bind.Value("--reject", adjustment.reject_k, "residuals beyond R robust sigmas rejected (0 = off)")
      ->check(CLI::NonNegativeNumber);
  bind.Negative("--no-fold-guard", adjustment.fold_guard, "do not limit vertex steps that would fold the surface");
}

// The start surface (engine/start/) and object lifting on the coarsest level.
void BindStart(const OptionBinder& bind, ReconstructionOptions& options) {
  bind.Function<std::string>(
          "--start",
          [&options](const std::string& name) {
            options.start_closed = name == "closed";
            if (!options.start_closed) options.start = StartSurfaceFromName(name);
          },
          [&options] {
            if (options.start_closed) return std::string("closed");
            const char* names[] = {"auto", "plane", "tiepoints"};
            return std::string(names[static_cast<int>(options.start)]);
          },
          "start surface: auto (tie points when >= 20 lie in the region and neither --start-height nor lifting is "
          "given) | plane | tiepoints | closed (an ellipsoid or hull around the tie points, for objects)")
      ->check(CLI::IsMember({"auto", "plane", "tiepoints", "closed"}));
  bind.Choice("--start-plane", options.start_plane,
              {{"auto", ReconstructionOptions::StartPlane::kAuto},
               {"horizontal", ReconstructionOptions::StartPlane::kHorizontal},
               {"fitted", ReconstructionOptions::StartPlane::kFitted}},
              "start plane: fitted to the tie points, horizontal, or auto (fitted when tilted > 45 deg: a facade)");
  bind.Function<int>(
          "--lifting-steps",
          [&options](const int& steps) { options.lifting_steps = options.closed.lifting_steps = steps; },
          [&options] { return ConfigText(options.lifting_steps); },
          "object lifting: start heights (closed starts: scales) tried on the coarsest level (0 = off)")
      ->check(CLI::NonNegativeNumber);
  bind.Value("--lifting-range", options.lifting_range, "object lifting: heights over +- range/2 (m)");
  bind.Value("--start-step-cap", options.start_step_cap_pixels,
             "tie-point start: after the coarsest level, nodes at most this many of its pixels from their tie-point "
             "heights (0 = off)")
      ->check(CLI::Range(0.0, 64.0));
}

// Closed starts for objects (engine/start/start_closed.h, visual_hull.h).
void BindClosed(const OptionBinder& bind, ReconstructionOptions& options) {
  ClosedStartOptions& closed = options.closed;
  bind.Value("--closed-shape", closed.shape,
             "closed start: ellipsoid | hull (convex hull of the tie points) | visual-hull (carved to the "
             "silhouettes)");
  bind.Value("--closed-lifting-range", closed.lifting_range,
             "object lifting of a closed start: scale factors over 1 +- range/2");
  bind.Function<double>(
      "--hull-background",
      [&options](const double& grey) {
        options.closed.visual_hull.foreground.background_max = grey;
        options.silhouette_foreground.background_max = grey;
      },
      [&closed] { return ConfigText(closed.visual_hull.foreground.background_max); },
      "visual hull and silhouette term: grey values <= this are background (the silhouette term's unless "
      "--silhouette-background)");
  bind.Value("--hull-voxel", closed.visual_hull.voxel_size,
             "visual hull: voxel edge (m; 0 = the box's longest side / 200)");
  bind.Value("--hull-misses", closed.visual_hull.allowed_misses,
             "visual hull: images that may see background at a kept voxel");
  bind.Negative("--no-hull-clamp", closed.hull_clamp, "let the surface leave the visual hull");
  bind.Value("--hull-constraint-voxel", closed.constraint_voxel,
             "voxel edge of the hull the surface is held to after each level (m; 0 = the images' pixel footprint at "
             "the region's centre, at most 64 million voxels)");
  bind.Value("--hull-rim-cos", closed.hull_rim_cos, "a vertex is on a hull rim where |normal . ray| <= this");
  bind.Value("--hull-rim-edges", closed.hull_rim_edges, "farthest push onto a hull rim, in edge lengths");
  bind.Switch("--hull-clamp-guard", closed.clamp_guard,
              "halve, at last undo, pulls inside the hull that fold or cross faces");
  bind.Switch("--hull-rims", closed.hull_rims, "push the surface out onto the hull's rims after each level");
}

// The silhouette term of the adjustment (objects before a dark background).
void BindSilhouette(const OptionBinder& bind, ReconstructionOptions& options) {
  AdjustmentOptions& adjustment = options.adjustment;
  ForegroundOptions& foreground = options.silhouette_foreground;
  bind.Value("--silhouette-weight", adjustment.silhouette_weight,
             "weight of a rim vertex's distance to the image outline (grey values^2 per level pixel^2; 0 = off)");
  bind.Value("--silhouette-background", foreground.background_max, "grey values <= this are background");
  bind.Value("--silhouette-open", foreground.open_radius, "opening radius of the foreground mask (pixels)");
  bind.Value("--silhouette-fill-holes", foreground.fill_holes_below,
             "enclosed background holes under this many pixels are foreground");
  bind.Value("--silhouette-rim-cos", adjustment.silhouette_rim_cos,
             "a vertex is on an image's rim where |normal . ray| <= this");
  bind.Value("--silhouette-outside-px", adjustment.silhouette_outside_px,
             "farthest rim projection onto background used (level pixels)");
  bind.Value("--silhouette-inside-px", adjustment.silhouette_inside_px,
             "farthest rim projection inside the outline used (level pixels)");
}

// Windows of a level, and what runs after each level's adjustment.
void BindLevels(const OptionBinder& bind, ReconstructionOptions& options) {
  bind.Value("--window-faces", options.windows.partition.max_faces, "most core triangles per window");
  bind.Value("--window-margin", options.windows.partition.margin_rings, "face rings around a window's core");
  bind.Value("--sweeps", options.windows.sweeps, "sweeps over the windows of a level");
  bind.Negative("--no-occluders", options.windows.occluders, "windows do not see the surface around them");
  bind.Value("--tangential-smoothing", options.tangential_smoothing,
             "per finer level: iterations of tangential smoothing on the creased G1 surface (0 = off)")
      ->check(CLI::Range(0, 10));
  bind.Value("--straighten-rounds", options.straighten_rounds,
             "per level: put straight crease chains on their line and adjust again, kept unless sigma0 rises by "
             "more than --straighten-tolerance, at most this often (0 = off)")
      ->check(CLI::Range(0, 10));
  bind.Value("--straighten-local-rings", options.straighten_local_rings,
             "straightening: adjust again only the windows within this many edge rings of the vertices it moved "
             "(-1 = the whole level)")
      ->check(CLI::Range(-1, 50));
  bind.Value("--straighten-tolerance", options.straighten_tolerance,
             "straightening: kept unless sigma0 rises by more than this share")
      ->check(CLI::Range(0.0, 1.0));
  bind.Negative("--no-relax-unseen", options.relax_unseen,
                "leave vertices no image saw where the adjustment left them");
  bind.Negative("--no-untangle", options.untangle,
                "leave triangle pairs that cross after a level as they are (counted in report.json)");
  bind.Negative("--keep-crossing-facets", options.flatten_crossing_facets,
                "write the surface facets as adjusted even where they cross (by default they are pulled toward "
                "the TIN's chords there)");
}

// The search along normals before and after each finer level (engine/search/normal_search.h).
void BindNormalSearch(const OptionBinder& bind, ReconstructionOptions& options) {
  NormalSearchOptions& search = options.normal_search_options;
  bind.OptionalSwitch("--normal-search,!--no-normal-search", options.normal_search,
                      "steep vertices (walls) search along their normals for the offset where the images agree "
                      "best (default: on for plane and tie-point starts, off for closed and facade starts)");
  bind.Value("--normal-search-last-level", options.normal_search_last_level, "finest pyramid level searched")
      ->check(CLI::Range(0, 20));
  bind.Value("--normal-search-rounds", options.normal_search_rounds,
             "after a level's adjustment: search and adjust again, at most this often")
      ->check(CLI::Range(0, 10));
  bind.Value("--normal-search-rounds-last-level", options.normal_search_rounds_last_level,
             "finest pyramid level with search rounds")
      ->check(CLI::Range(0, 20));
  bind.Value("--normal-search-tolerance", options.normal_search_tolerance,
             "a round is kept when sigma0 stays below (1 + this) x sigma0 before it (0 = only when it drops; "
             "1 = always, not judged)")
      ->check(CLI::Range(0.0, 1.0));
  bind.Value("--normal-search-local-rings", options.normal_search_local_rings,
             "rounds re-adjust only the windows within this many edge rings of the vertices that moved (-1 = the "
             "whole level)")
      ->check(CLI::Range(-1, 50));
  bind.Value("--normal-search-min-cos", search.min_cos,
             "an image is used where it sees the tangent plane at |cos| >= this")
      ->check(CLI::Range(0.0, 1.0));
  bind.Value("--normal-search-min-angle", search.min_angle_to_views_deg,
             "only vertices whose normal turns more than this (deg) from the mean direction to their images")
      ->check(CLI::Range(0.0, 90.0));
  bind.Value("--normal-search-patch", search.patch_half, "patch of (2 N + 1)^2 samples one level pixel apart")
      ->check(CLI::Range(1, 16));
  bind.Value("--normal-search-range", search.range_pixels, "offsets over +- this many level pixels")
      ->check(CLI::Range(1.0, 64.0));
  bind.Value("--normal-search-min-score", search.min_score, "least mean pairwise correlation of a peak")
      ->check(CLI::Range(-1.0, 1.0));
}

// Plane propagation after each normal search (engine/search/plane_propagation.h) and the
// V-cycles after the finest level (engine/pipeline/v_cycle.h).
void BindPlanesAndCycles(const OptionBinder& bind, ReconstructionOptions& options) {
  PlanePropagationOptions& planes = options.plane_propagation_options;
  bind.Switch("--plane-propagation,!--no-plane-propagation", options.plane_propagation,
              "after each normal search: vertices try the planes of neighbours whose images agree there");
  bind.Value("--plane-iterations", planes.iterations, "iterations, each a ring further")->check(CLI::Range(1, 50));
  bind.Value("--plane-source-score", planes.source_score,
             "vertices lend their plane at this mean pairwise correlation or more, and borrow below it")
      ->check(CLI::Range(-1.0, 1.0));
  bind.Value("--plane-min-gain", planes.min_gain, "a borrowed plane scores this much above the vertex's own patch")
      ->check(CLI::Range(0.0, 2.0));
  bind.Value("--plane-min-tilt", planes.min_target_tilt_deg,
             "only vertices whose normal turns at least this far (deg) from vertical borrow (0 = every vertex)")
      ->check(CLI::Range(0.0, 90.0));
  bind.Value("--plane-occluder-slack", planes.occluder_slack_pixels,
             "an image sees a borrowed plane when no surface lies in the way nearer than this many level pixels")
      ->check(CLI::Range(0.0, 64.0));
  bind.Value("--plane-max-move", planes.max_move_pixels, "a vertex moves onto a plane at most this many level pixels")
      ->check(CLI::Range(0.5, 64.0));
  bind.Value("--v-cycles", options.v_cycles,
             "after the finest level: back up to --v-cycle-level and adjust down again, this often (0 = off)")
      ->check(CLI::Range(0, 10));
  bind.Value("--v-cycle-level", options.v_cycle_level, "the pyramid level a V-cycle goes back up to")
      ->check(CLI::Range(1, 20));
  bind.Value("--v-cycle-rounds-last-level", options.v_cycle_rounds_last_level,
             "finest level with normal-search rounds in the V-cycles (-1 = as --normal-search-rounds-last-level)")
      ->check(CLI::Range(-1, 20));
  bind.Value("--v-cycle-robust", options.v_cycle_robust_k,
             "V-cycle levels: Huber weights beyond K robust sigmas, rejection beyond 5 (0 = plain least squares)")
      ->check(CLI::NonNegativeNumber);
}

// Wall refinement on the finest level (refine/wall_corners.h, unseen_lips.h).
void BindWalls(const OptionBinder& bind, ReconstructionOptions& options) {
  bind.Switch("--wall-corners,!--no-wall-corners", options.wall_corners,
              "split the edges walls stretched, then lay each vertical corner onto its two walls and their line, "
              "kept when the images agree");
  bind.Switch("--wall-feet,!--no-wall-feet", options.wall_feet,
              "lay the crease where a wall meets the ground (or a lower roof) onto both");
  bind.Switch("--wall-eaves,!--no-wall-eaves", options.wall_eaves,
              "lay the crease where a wall meets its roof onto both");
  bind.Value("--wall-corner-min-angle", options.wall_corner_min_angle_deg,
             "least angle (deg) between two walls' normals for a vertical corner")
      ->check(CLI::Range(45.0, 90.0));
  bind.Negative("--no-wall-merge", options.wall_merge_pieces,
                "keep planar wall pieces apart instead of merging those within an edge that one plane fits");
  bind.Negative("--no-fold-lips", options.fold_lips,
                "leave lips in front of walls whose underside no image sees, and pockets behind them, as adjusted "
                "(by default laid onto the seen wall's plane when the images agree)");
}

}  // namespace

void BindExpertOptions(const OptionBinder& bind, ReconstructionOptions& options) {
  BindAdjustment(bind, options);
  BindStart(bind, options);
  BindClosed(bind, options);
  BindSilhouette(bind, options);
  BindLevels(bind, options);
  BindNormalSearch(bind, options);
  BindPlanesAndCycles(bind, options);
  BindWalls(bind, options);
}

}  // namespace facets
