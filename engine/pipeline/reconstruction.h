// The reconstruction (DESIGN.md sections 2 and 5) as a pipeline of stages, each in its
// own file under engine/pipeline/:
//   start        region, start surface, object lifting            start_stage.h
//   images       image pyramids, silhouettes                      level_images_stage.h
//   per pass over a level, coarse to fine (then the V-cycles):
//     descent    subdivision, quality pass, smoothing; or back up descent_stage.h
//     search     normal search and plane propagation              search_stage.h
//     adjust     overlapping windows, in parallel groups          level_windows.h
//     refine     search rounds, straightening, wall corners,      search_stage.h, straighten_stage.h,
//                lips: trials kept when the images agree          wall_corners_stage.h, lips_stage.h, trial.h
//     validity   unseen vertices, visual hull, untangling         validity_stage.h
//   products     crossing facets flattened; files: products.h
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "engine/solver/adjustment_options.h"
#include "engine/pipeline/geometry_check.h"
#include "engine/pipeline/level_windows.h"
#include "engine/pipeline/run_profile.h"
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
  // The last adjusted pyramid level (0 = the original images): levels-1 down to
  // finest_level are adjusted; the products and their precision come from finest_level,
  // whose ground pixel is 2^finest_level of the images'. The finer images are not kept.
  int finest_level = 0;
  PyramidFilter filter = PyramidFilter::kBinomial5;
  // Options of every window adjustment; adjustment.break_off is the finest level's
  // bound in metres (doubled per coarser level) when break_off_gsd is 0.
  AdjustmentOptions adjustment;
  // > 0: the break-off of each level in the level's ground pixels, so that one setting
  // suits every scale (0.01 m is 0.04 pixel of a 0.24 m aerial pixel, 3 pixels of a
  // 3 mm close-range pixel).
  double break_off_gsd = 0.06;
  // Window size, margin, sweeps (engine/pipeline/level_windows.h).
  LevelWindowOptions windows;
  // Edge of a grey facet in pixels of the level's images.
  double facet_pixels = 2.0;
  // All channels (one grey value per channel, geometry shared), or their mean.
  bool colour = false;
  // Start plane height (local Z); default: the block's mean terrain height, else the
  // median height of the tie points.
  std::optional<double> start_height;
  // Open start (engine/start/start_tiepoints.h): auto = fitted to the tie points when at
  // least tiepoint_start.min_points_total lie in the region and neither start_height nor
  // object lifting asks for a plane.
  StartSurfaceKind start = StartSurfaceKind::kAuto;
  TiePointStartOptions tiepoint_start;
  // Orientation of the start plane (engine/start/start_fitted_plane.h). kAuto: a plane
  // fitted robustly to the region's tie points when it tilts more than
  // fitted_plane_min_tilt_deg from the horizontal (a facade seen from the street), else
  // horizontal. Ignored when start_height is given.
  enum class StartPlane { kAuto, kHorizontal, kFitted };
  StartPlane start_plane = StartPlane::kAuto;
  double fitted_plane_min_tilt_deg = 45.0;
  // Object lifting on the coarsest level: start heights over +- lifting_range / 2 (m)
  // around the start height in lifting_steps steps, one iteration each; the best one
  // starts the run. 0 steps = off.
  int lifting_steps = 0;
  double lifting_range = 30.0;
  // Closed start for objects seen from all around (engine/start/start_closed.h): the
  // ellipsoid fitted to the tie points, the visual hull, or closed.mesh_file. Object
  // lifting then scales it about its centre (closed.lifting_steps).
  bool start_closed = false;
  ClosedStartOptions closed;
  // Foreground of the images' silhouettes for the silhouette term
  // (adjustment.silhouette_weight > 0; visibility/silhouette.h).
  ForegroundOptions silhouette_foreground = VisualHullOptions::DefaultForeground();
  // Region of interest (local); default: the block's, else the tie points' extent.
  std::optional<RegionOfInterest> roi;
  // Tiled level images in this folder, read per window through a cache of
  // image_cache_mb (MB); empty: every level image in memory.
  std::optional<std::string> image_cache_dir;
  double image_cache_mb = 256.0;
  // Iterations of tangential smoothing after each level's subdivision and quality pass
  // (TangentialSmooth, mesh/local_ops.h) on the G1 surface with the coarser level's
  // creases, crease vertices held. 0 = off.
  int tangential_smoothing = 2;
  // After each adjustment of a level, vertices no image saw move to the membrane spanned
  // by the seen surface around them (RelaxUnseenVertices, mesh/local_ops.h).
  bool relax_unseen = true;
  // Lips and pockets beside walls that no image sees laid onto the seen wall's plane
  // (engine/pipeline/lips_stage.h; not for closed or fitted-plane starts): each a trial
  // over the windows within fold_lips_local_rings edge rings, kept unless sigma0 rises by
  // more than fold_lips_tolerance (a share). A lip that makes triangles cross is first
  // untangled in at most fold_lips_untangle_rounds rounds (also used by the corners).
  bool fold_lips = true;
  int fold_lips_local_rings = 2;
  int fold_lips_untangle_rounds = 4;
  double fold_lips_tolerance = 0.01;
  // On the finest level's last pass (aerial starts; engine/pipeline/wall_corners_stage.h):
  // stretched edges split, then vertical corners (wall_corners), walls' feet (wall_feet)
  // and eaves (wall_eaves) laid onto their planes one at a time, each a trial over the
  // windows within wall_corners_local_rings rings, kept unless sigma0 rises by more than
  // wall_corners_tolerance. Walls meet at a vertical corner when their normals are at
  // least wall_corner_min_angle_deg apart; coplanar wall pieces within an edge of each
  // other are merged first (wall_merge_pieces).
  bool wall_corners = false;
  bool wall_feet = false;
  bool wall_eaves = false;
  int wall_corners_local_rings = 2;
  double wall_corners_tolerance = 0.0;
  double wall_corner_min_angle_deg = 60.0;
  bool wall_merge_pieces = true;
  // After each level: crossing triangle pairs untangled by local smoothing
  // (UntangleSelfIntersections, mesh/surface_validity.h).
  bool untangle = true;
  // After the finest level: the product surface's facets that cross (G1 patches bulging
  // through a nearby sheet) pulled toward their TIN chords until none cross
  // (refine/facet_crossings.h). The TIN, grey values and sigma stay as adjusted.
  bool flatten_crossing_facets = true;
  // Crease straightening (engine/pipeline/straighten_stage.h): at most this many rounds
  // per level (0 = off; never for closed starts), each a trial over the windows within
  // straighten_local_rings rings (-1: the whole level), kept unless sigma0 rises by more
  // than straighten_tolerance (a share).
  int straighten_rounds = 3;
  int straighten_local_rings = 2;
  double straighten_tolerance = 0.01;
  // Search along normals before each level below the coarsest (engine/search/normal_search.h)
  // for the vertices whose normals turn away from their images (walls of an aerial
  // block). Unset: on for plane and tie-point starts, off for closed starts and facades.
  // Levels below normal_search_last_level are not searched.
  std::optional<bool> normal_search;
  int normal_search_last_level = 0;
  // After a level's adjustment: up to normal_search_rounds rounds of search and trial on
  // the levels normal_search_rounds_last_level and coarser (not the coarsest), kept unless
  // sigma0 rises by more than normal_search_tolerance (a share; 1: kept, not judged,
  // kKeptWhateverSigma0), over the windows within normal_search_local_rings rings of the
  // moved vertices (-1: the whole level).
  int normal_search_rounds = 2;
  int normal_search_rounds_last_level = 1;
  double normal_search_tolerance = 0.0;
  int normal_search_local_rings = -1;
  NormalSearchOptions normal_search_options;
  // After each normal search: vertices try the planes of neighbours whose images agree
  // there, a ring further each iteration (engine/search/plane_propagation.h).
  bool plane_propagation = true;
  PlanePropagationOptions plane_propagation_options;
  // Tie-point start: after the coarsest level, nodes further than this many of its
  // ground pixels from their start are put back to that distance (0 = off).
  double start_step_cap_pixels = 5.0;
  // V-cycles (engine/pipeline/v_cycle.h): after the finest level, back up to level
  // v_cycle_level (its TIN moved along its normals onto the finished surface) and down
  // again, v_cycles times, with Huber weights beyond v_cycle_robust_k robust sigmas and
  // rejection beyond v_cycle_reject_k (0: plain least squares). Their search rounds run
  // on v_cycle_rounds_last_level and coarser (-1: as the descent).
  int v_cycles = 0;
  int v_cycle_level = 1;
  double v_cycle_robust_k = 2.0;
  double v_cycle_reject_k = 5.0;
  int v_cycle_rounds_last_level = -1;
  // One line of progress at a time (stage, level, window, sigma0).
  std::function<void(const std::string&)> progress;
  // Each level's TIN once the level is finished.
  std::function<void(int level, const TinMesh& mesh)> level_done;
  // The finest level's TIN as the wall-corner stage starts finding its creases (after
  // the splits and their adjustment, before any crease is laid).
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
  double seconds = 0.0;
};

struct ReconstructionReport {
  // The block's geometry check (CheckBlock).
  GeometryCheck geometry;
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
  // Wall and CPU seconds per stage and level (engine/pipeline/run_profile.h); the
  // products' files are added as they are written (WriteProducts).
  RunProfile profile;
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

// Runs CheckBlock (engine/pipeline/geometry_check.h: image headers, geometry; region
// options.roi, its lines to options.progress) on `block`, then reconstructs from the
// images it keeps. Throws std::runtime_error with a clear message on unusable input (an
// image file missing, unreadable or of the wrong size, fewer than 2 usable images, no
// ROI and no tie points, images whose pixels cannot be decoded).
Reconstruction Reconstruct(const ImageBlock& block, const ReconstructionOptions& options);
// The same from a block CheckBlock has checked (by a caller that needs the checked block
// before it chooses the options, as `facets reconstruct` does); the products take
// checked.block's origin.
Reconstruction Reconstruct(const CheckedImageBlock& checked, const ReconstructionOptions& options);

}  // namespace facets
