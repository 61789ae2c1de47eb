// The reconstruction driver (DESIGN.md sections 2 and 5): image pyramid, start
// surface, object lifting on the coarsest level, then per level coarse to fine the
// window adjustment and the refinement of the TIN (quaternary subdivision, quality
// pass, tangential smoothing) one pyramid level down.
//
// Each level is adjusted in overlapping windows (engine/level_windows.h), windows
// that share no vertex in parallel. The level images are held in memory, or written as
// tiled TIFFs and read per window region (engine/level_image_store.h).
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "engine/solver/adjustment_options.h"
#include "engine/pipeline/level_windows.h"
#include "engine/search/normal_search.h"
#include "engine/search/plane_propagation.h"
#include "engine/images/pyramid.h"
#include "engine/start/start_closed.h"
#include "engine/start/start_tiepoints.h"
#include "engine/pipeline/v_cycle.h"
#include "engine/solver/window_adjustment.h"
#include "io/image_block.h"
#include "refine/facet_crossings.h"
#include "mesh/tessellation.h"
#include "mesh/tin.h"

namespace facets {

struct ReconstructionOptions {
  // Pyramid levels: 1 = the original images only.
  int levels = 3;
  // The last adjusted pyramid level (0 = the original images): levels levels-1 down to
  // finest_level are adjusted, the products come from finest_level, its ground pixel is
  // 2^finest_level of the images'. A large scene (a whole facade at 3 mm image ground
  // pixels) at a coarser resolution in reasonable time; the finer images are not kept.
  int finest_level = 0;
  PyramidFilter filter = PyramidFilter::kBinomial5;
  // Options of every window adjustment; break_off is the finest level's bound and is
  // doubled per coarser level.
  AdjustmentOptions adjustment;
  // > 0: the break-off of each level is this many of the level's ground pixels instead
  // of adjustment.break_off (doubled per level): a bound in metres suits one scale only
  // (0.01 m is 0.04 pixel of the seeds' 0.24 m but 3 pixels of a 3 mm object pixel).
  // `facets reconstruct` sets 0.06 when --break-off is not given.
  double break_off_gsd = 0.0;
  // Window size, margin, sweeps (engine/level_windows.h).
  LevelWindowOptions windows;
  // Edge of a grey facet in pixels of the level's images (the seeds: about 2).
  double facet_pixels = 2.0;
  // Use all channels (colour: one grey value per channel, geometry shared) or their mean.
  bool colour = false;
  // Start surface: a plane at this height (local Z); default: the block's mean terrain
  // height, else the median height of the tie points.
  std::optional<double> start_height;
  // Start surface (engine/start_tiepoints.h): auto = fitted to the tie points when at
  // least tiepoint_start.min_points_total lie in the region and neither start_height
  // nor object lifting asks for a plane.
  StartSurfaceKind start = StartSurfaceKind::kAuto;
  TiePointStartOptions tiepoint_start;
  // Orientation of the start plane (engine/start_fitted_plane.h). kAuto: a plane fitted
  // robustly to the tie points in the region when it is tilted more than
  // fitted_plane_min_tilt_deg from the horizontal (a facade seen from the street), else
  // the horizontal plane. Ignored when start_height is given.
  enum class StartPlane { kAuto, kHorizontal, kFitted };
  StartPlane start_plane = StartPlane::kAuto;
  double fitted_plane_min_tilt_deg = 45.0;
  // Object lifting on the coarsest level (seed 001): try start heights over
  // +- lifting_range / 2 around the start height in lifting_steps steps, one iteration
  // each, and start from the best. 0 steps = off.
  int lifting_steps = 0;
  double lifting_range = 30.0;
  // Closed start for objects seen from all around (engine/start_closed.h) instead of
  // the plane: the ellipsoid fitted to the tie points, or closed.mesh_file when given.
  // Object lifting then scales it about its centre (closed.lifting_steps, the plane's
  // lifting_steps are not used).
  bool start_closed = false;
  ClosedStartOptions closed;
  // Foreground of the images' silhouettes for the silhouette term of the adjustment
  // (adjustment.silhouette_weight > 0; visibility/silhouette.h): threshold, opening,
  // components, holes, as for the visual hull.
  ForegroundOptions silhouette_foreground = VisualHullOptions::DefaultForeground();
  // Region of interest (local); default: the block's, else the tie points' extent.
  std::optional<RegionOfInterest> roi;
  // Tiled level images in this folder, read per window through a cache of
  // image_cache_mb; empty: every level image in memory.
  std::optional<std::string> image_cache_dir;
  double image_cache_mb = 256.0;
  // Wall passes (issue 7): walls standing up inside a level stretch its triangles, so
  // after a level's adjustment the quality pass (splits beyond 1.5x the target edge,
  // tangent Delaunay flips) runs again and, when it split edges, the level is adjusted
  // again; at most this many extra adjustments per level. 0 = quality pass between
  // levels only. Default 0: on the block's 4 m building with the fold guard and the
  // relaxation of unseen vertices, one pass gave no better walls (completeness 45-52 %
  // vs 48-50 %), 6-10 crossing triangle pairs vs 0, and 2.5x the time (docs/EXPERIMENTS.md).
  int wall_passes = 0;
  // Tangential smoothing after each level's subdivision and quality pass (issue 6,
  // DESIGN.md section 5): this many iterations of TangentialSmooth (mesh/local_ops.h)
  // on the G1 surface with the coarser level's creases, crease vertices held, so the
  // split and stretched triangles even out without rounding ridges and eaves. 0 = off.
  // 2: with the crease straightening, seed table 28 of 28 in range (1: 27, experiment 12
  // at lambda 4000 4.46); 1 gave the 4 m building's walls 49-53 % complete, 2 45-49 %.
  int tangential_smoothing = 2;
  // After each adjustment of a level, vertices no image saw move to the membrane
  // spanned by the seen surface around them (RelaxUnseenVertices, mesh/local_ops.h).
  bool relax_unseen = true;
  // After each level's adjustment (not for closed or fitted-plane starts): lips of the
  // surface in front of a wall whose underside no image sees, and pockets behind it that
  // their rims hide, are laid onto the plane of the seen wall beside them, one at a time
  // (FindUnseenLips, LayLipOntoWall: mesh/unseen_lips.h); each is left when it makes
  // triangles cross or fold, else the windows within fold_lips_local_rings edge rings of
  // its vertices run again and it is kept unless their sigma0 rises by more than
  // fold_lips_tolerance (issue 7: one such lip carried 68 % of the squared wall error of
  // the block's thorough run).
  bool fold_lips = true;
  int fold_lips_local_rings = 2;
  // A laid lip that makes triangles cross is untangled first (UntangleSelfIntersections,
  // at most this many rounds; 0 = left at once) and left only when pairs remain.
  int fold_lips_untangle_rounds = 4;
  double fold_lips_tolerance = 0.01;
  // On the finest level's last visit (issue 7; on with --thorough-walls; not for closed
  // or fitted-plane starts): edges the walls stretched are split (QualityPass, then the
  // level adjusted again), and each vertical corner where two planar walls meet
  // (FindWallCorners, mesh/wall_corners.h) gets its band of crumpled vertices laid onto
  // the two walls and onto the corner line, one corner at a time; a corner is left when it
  // makes triangles cross or fold (after at most fold_lips_untangle_rounds of
  // untangling), else the windows within wall_corners_local_rings edge rings run again and
  // it is kept unless their sigma0 rises (by more than wall_corners_tolerance; session 33:
  // 0, as a wrong corner on block_oblique fitted 0.2 % worse and was kept at 1 %).
  // wall_feet and wall_eaves do the same for the creases where a wall meets the ground
  // (or a lower roof) at its foot and the roof at its eave (mesh/wall_corners.h); any of
  // the three switches the step on.
  bool wall_corners = false;
  bool wall_feet = false;
  bool wall_eaves = false;
  int wall_corners_local_rings = 2;
  double wall_corners_tolerance = 0.0;
  double wall_corner_min_angle_deg = 60.0;  // WallCornerOptions::min_corner_angle_deg
  bool wall_merge_pieces = true;            // WallCornerOptions::merge_wall_pieces
  // After each level: triangle pairs that cross (between windows, after splits: the
  // fold guard only sees one window's step) are untangled by local smoothing of their
  // corners and rings (UntangleSelfIntersections, mesh/surface_validity.h).
  bool untangle = true;
  // After the finest level, the product surface's facets that cross (G1 patches bulging
  // through a nearby sheet whose chords do not cross) are pulled toward their TIN chords
  // until none cross (FlattenCrossingFacets, mesh/facet_crossings.h; issue 7: no
  // self-intersections in the output). The TIN, grey values and sigma stay as adjusted.
  bool flatten_crossing_facets = true;
  // After a level's adjustment, chains of vertices along a straight crease (a ridge
  // skew to the grid, a zigzag of edges) are put on the crease's line
  // (StraightenCreaseChains, mesh/creases.h) and the level runs again around them, kept
  // unless its sigma0 rises (below); at most this many rounds (0 = off). Off for closed
  // starts.
  int straighten_rounds = 3;
  // Roof lines (ridges, hips) and steep lines (eaves, feet) in rounds of their own, each
  // up to straighten_rounds and kept or dropped by itself (CreaseLines, mesh/creases.h).
  // Off by default: on the block (session 24) the roof median over five regions went
  // 0.0676 -> 0.0654 GSD and the ridges 0.319 -> 0.288 GSD (A 0.270 -> 0.125, B 0.284 ->
  // 0.341), and with --thorough-walls A the ridges went 0.062 -> 0.142 GSD: the gate, a
  // window's sigma0, is moved more by its crumpled walls than by a ridge.
  bool straighten_by_kind = false;
  // The straightening's run of the level again: only the windows over the faces within
  // this many edge rings of the vertices it moved, judged by those windows' sigma0
  // (engine/local_readjustment.h; -1 = the whole level, judged by the level's). Local
  // costs a few windows (block A: 4 a round, three rounds 5.5 s) where the whole level
  // costs 25-40 s a round.
  int straighten_local_rings = 2;
  // A straightening is kept unless sigma0 rises by more than this share: the fit hardly
  // sees a ridge or eave a few centimetres off among the windows' other observations
  // (block A, issue 7: +0.2 % in the 4 windows with the gable ridges 3x closer to the
  // truth; roof median 0.110 -> 0.086 GSD).
  double straighten_tolerance = 0.01;
  // Before each level below the coarsest (after its subdivision): vertices search along
  // their normals for the offset where the images agree best (engine/normal_search.h),
  // so walls and eaves a coarser level left several pixels off start within the
  // adjustment's pull-in. Only vertices whose normal turns more than
  // normal_search_options.min_angle_to_views_deg (45) from the direction to their images:
  // the walls of an aerial block, not its roofs and ground (the seed table is unchanged to
  // the digit). Whole block: walls >= 2 views 32.4 -> 55.2 % complete at 1 GSD
  // (docs/EXPERIMENTS.md, session 9). Unset (auto): on for plane and tie-point starts, off
  // for closed starts (every rim is steep against its views; the visual hull and the
  // silhouette term hold them) and for a start plane fitted to a facade (the street and the
  // side walls are the steep parts there; on the fountain the search made the flat wall
  // rougher: plane rms 8.3 -> 20.2 mm).
  std::optional<bool> normal_search;
  int normal_search_last_level = 0;  // levels below this are not searched
  // After a level's adjustment: search again and adjust again, kept while sigma0 drops,
  // at most this often, on levels normal_search_rounds_last_level and coarser but not the
  // coarsest (on level 0 a round cost as much as the level and was dropped; on the
  // coarsest, searched every vertex, a roof fell).
  int normal_search_rounds = 2;
  int normal_search_rounds_last_level = 1;
  // A round is kept unless sigma0 after it exceeds (1 + this) x sigma0 before; 0: kept
  // only when sigma0 drops. The rounds move a few hundred wall vertices among millions of
  // observations, so sigma0 changes by a few tenths of a percent either way (level 0 of
  // the whole block: 10.868 -> 10.871) while the block's walls gain 6-15 points with
  // rounds kept on every level; not the default: the real Boruszyn walls lose (22.9 ->
  // 16.2 % of the area within 5 deg with 0.02; docs/EXPERIMENTS.md, session 11).
  double normal_search_tolerance = 0.0;
  // Rounds re-adjust only the windows over the faces within this many edge rings of the
  // vertices the search and the propagation moved (LocalScope, engine/level_windows.h);
  // the round is then judged by those windows' sigma0 before and after (one linearisation
  // each, of the surface before the search and of the one the round left). Negative: the
  // whole level again.
  int normal_search_local_rings = -1;
  NormalSearchOptions normal_search_options;
  // After each normal search (before a level and in its rounds; so not for closed and
  // facade starts): vertices try the planes of neighbours whose images agree there, a
  // ring further each iteration (engine/plane_propagation.h). Whole block walls >= 2
  // views 48.5 -> 66.9 % over three regions at the same time; the real Boruszyn walls
  // within 5 deg 16.8 +- 3.9 -> 15.6 +- 2.7 % over five ROIs a centimetre apart
  // (docs/EXPERIMENTS.md, session 13). Until session 23 most vertices had no score of
  // their own (an image whose frame cut the patch spoiled it); since then 80.8 % over
  // five regions of the block, roofs 0.095 -> 0.068 GSD.
  bool plane_propagation = true;
  PlanePropagationOptions plane_propagation_options;
  // With the tie-point start: after the coarsest level, nodes further than this many of
  // its ground pixels from their start are put back to that distance (0 = off). The
  // block's tall flat roof: level 3 lifts a node 9.7 m off its tie points while fitting
  // the building with one smooth hill, and every finer level keeps the box it leaves
  // (docs/EXPERIMENTS.md, session 17). With 5: the box gone, roof medians 0.147 / 0.294
  // / 0.190 -> 0.110 / 0.107 / 0.093 GSD in the block's three regions, walls >= 2 views
  // 66.9 -> 65.8 % over them (within the runs' spread), Boruszyn walls unchanged.
  double start_step_cap_pixels = 5.0;
  // After the finest level (its relaxation and untangling included): adjust it once more
  // from there, with Huber weights beyond polish_robust_k robust sigmas and rejection
  // beyond polish_reject_k (0: plain least squares). Negative: no such pass (default:
  // it costs as much as the finest level again). On the bundled block (docs/EXPERIMENTS.md,
  // session 10) the finest level's residuals have a heavy tail (sigma0 10.9 against 5.8
  // robust, noise 4): with 2 the walls >= 2 views rise from 55.2 to 59.4 % complete at
  // 1 GSD and the roof median falls from 0.146 to 0.096 GSD, at 130 s instead of 78 s.
  double polish_robust_k = -1.0;
  double polish_reject_k = 5.0;
  // V-cycles (engine/v_cycle.h): after the finest level, go back up to pyramid level
  // v_cycle_level: the TIN that level left, every vertex moved along its normal onto the
  // finished finest surface (within one of its edges), then levels v_cycle_level..finest
  // adjusted again, as often as v_cycles says. Its levels run with Huber weights beyond
  // v_cycle_robust_k robust sigmas and rejection beyond v_cycle_reject_k (0: plain least
  // squares). Off by default (0 cycles): a cycle costs those levels again.
  int v_cycles = 0;
  int v_cycle_level = 1;
  double v_cycle_robust_k = 2.0;
  double v_cycle_reject_k = 5.0;
  // The V-cycles' passes run the normal search's rounds on this level and coarser
  // (negative: normal_search_rounds_last_level, as the descent). With 0 and the
  // descent's default the finest level's rounds run once, in the cycle.
  int v_cycle_rounds_last_level = -1;
  // Called with one line of progress at a time (stage, level, iteration, sigma0).
  std::function<void(const std::string&)> progress;
  // Called with each level's TIN once the level is finished (e.g. to keep it for a look
  // at how the multigrid got there).
  std::function<void(int level, const TinMesh& mesh)> level_done;
  // Called with the finest level's TIN as the corner step (wall_corners, wall_feet,
  // wall_eaves) finds its creases: after the splits and their adjustment, before any
  // crease is laid (e.g. to replay the step on it without images).
  std::function<void(int level, const TinMesh& mesh)> creases_start;

  void Check() const;  // throws std::invalid_argument naming the option
};

struct LiftingTrial {
  double height = 0.0;
  double sigma0 = 0.0;
  double mean_dn = 0.0;
  long long observations = 0;
};

// Object lifting's choice (seed 001): the surface below the truth moves up and above
// it moves down, so the truth lies where the mean displacement changes sign from + to -
// between two neighbouring trial heights; of several such changes the one next to the
// smaller sigma0, the height interpolated to zero displacement. Without any sign
// change: the trial of minimal sigma0 plus its displacement. Trials with sigma0 >=
// 1e299 (no image saw them) are skipped.
double ChooseLiftedHeight(const std::vector<LiftingTrial>& trials);

// One extra adjustment of a level after the quality pass split stretched edges.
struct WallPass {
  int splits = 0;
  int flips = 0;
  int faces = 0;        // after the splits
  double sigma0 = 0.0;  // of the adjustment that followed
};

struct LevelReport {
  int level = 0;               // pyramid level, 0 = the original images
  int cycle = 0;               // 0: the descent; 1..: ReconstructionOptions::v_cycles
  // Of a cycle's first level: its TIN's vertices moved onto the finest surface.
  ProjectionReport projection;
  double ground_pixel = 0.0;   // mean ground pixel size of the level's images (m)
  double edge_length = 0.0;    // target TIN edge length (m)
  double break_off = 0.0;      // interior break-off bound of the level (m)
  int vertices = 0;
  int faces = 0;
  WindowReport window;                 // the level's summary (LevelAdjustment::summary)
  std::vector<WindowReport> windows;   // one per window (per-vertex vectors: owned vertices)
  std::vector<int> window_core_faces;
  int window_groups = 0;
  std::vector<WallPass> wall_passes;  // ReconstructionOptions::wall_passes
  // Validity of the level's final TIN (mesh/surface_validity.h) and the vertex steps
  // the fold guard limited (summed over windows and iterations, last adjustment).
  int folded_faces = 0;
  int self_intersections = 0;
  int fold_limited = 0;
  NormalSearchReport normal_search;  // ReconstructionOptions::normal_search
  int normal_search_rounds = 0;      // rounds kept (ReconstructionOptions::normal_search_rounds)
  // ReconstructionOptions::normal_search_local_rings: windows re-adjusted by the rounds
  // kept, summed (0 when the rounds re-adjust the whole level).
  int normal_search_local_windows = 0;
  PlanePropagationReport plane_propagation;  // before the level (ReconstructionOptions::plane_propagation)
  int smoothed = 0;  // vertex moves of the tangential smoothing before the level
  int relaxed = 0;  // unseen vertices relaxed (ReconstructionOptions::relax_unseen), summed
  int hull_clamped = 0;     // vertices pulled inside the visual hull (ClosedStartOptions::hull_clamp)
  int hull_unresolved = 0;  // outside it and not pulled in
  int hull_rim_pushed = 0;  // inside it, pushed out onto its rims (ClosedStartOptions::hull_rims)
  // ReconstructionOptions::fold_lips: lips and pockets laid onto their walls and kept,
  // their vertices, and those dropped (crossing or folded triangles, or a worse fit).
  int lips_folded = 0;
  int lip_vertices_moved = 0;
  int lips_dropped = 0;
  int lips_untangled = 0;  // of the kept ones, those whose crossing pairs were untangled first
  int lips_flattened = 0;  // of the kept ones, those whose folded rim was flattened first (FlattenFoldedRim)
  // ReconstructionOptions::wall_corners (and wall_feet, wall_eaves): splits of stretched
  // edges before them; vertical corners, feet and eaves found and laid (kept); the
  // vertices moved and the creases left (crossing or folded triangles, or a worse fit),
  // over all three kinds.
  int corner_splits = 0;
  int corners_found = 0;
  int corners_laid = 0;
  int feet_found = 0;
  int feet_laid = 0;
  int eaves_found = 0;
  int eaves_laid = 0;
  int corner_vertices_moved = 0;
  int corners_dropped = 0;
  int crossing_untangled = 0;  // crossing pairs before the untangling (ReconstructionOptions::untangle)
  int untangle_moved = 0;      // vertices it moved
  int untangle_membranes = 0;  // membranes it solved where the smoothing rounds left pairs
  // ReconstructionOptions::straighten_rounds: level runs after straightening kept and
  // dropped (the level's report is the last kept run's), vertices moved in the kept ones.
  int straighten_kept = 0;
  int straighten_dropped = 0;
  int straightened = 0;
  // ReconstructionOptions::polish_robust_k: whether the finest level was adjusted once
  // more, and its sigma0 before (the level's `window` is the polish's).
  bool polished = false;
  double sigma0_before_polish = 0.0;
  double seconds = 0.0;
};

struct ReconstructionReport {
  std::vector<LiftingTrial> lifting;
  double start_height = 0.0;
  std::string start_surface = "plane";  // or "tiepoints", "fitted plane"
  std::string start_detail;             // TiePointStartReport::Brief()
  // The images' mean up direction (minus their y axes in the world), unit; Z when they
  // cancel out (less than half a unit long: nadir images flown in all directions). The
  // preview's up for a facade (io/preview.h).
  Eigen::Vector3d camera_up = Eigen::Vector3d::UnitZ();
  std::vector<LevelReport> levels;  // in processing order, coarsest first
  // ReconstructionOptions::flatten_crossing_facets (pairs_found -1: not run).
  FacetCrossingRepair facet_crossings;
  double seconds_total = 0.0;
  double seconds_images = 0.0;
  bool images_cached = false;
  std::string Json() const;
  std::string BriefReport() const;
};

struct Reconstruction {
  TinMesh mesh;
  Tessellation tessellation;
  int channels = 1;
  std::vector<double> grey;  // per tessellation node and channel
  ReconstructionReport report;
  // Of the finest adjusted level (ReconstructionOptions::finest_level), per TIN vertex.
  std::vector<double> vertex_sigma;
  std::vector<int> vertex_views;
  std::vector<uint8_t> vertex_flags;
};

// Throws std::runtime_error with a clear message on unusable input (no ROI and no tie
// points, images that do not see the region, unreadable images).
Reconstruction Reconstruct(const ImageBlock& block, const ReconstructionOptions& options);

}  // namespace facets
