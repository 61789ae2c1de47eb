// Options of the least-squares adjustment of one window on one pyramid level
// (DESIGN.md sections 4-6). The CLI and the pipeline fill this struct; the estimator
// never parses flags.
#pragma once

#include <string>

#include "engine/solver/pcg.h"
#include "engine/solver/window_clocks.h"

namespace facets {

enum class Regularisation {
  // Pseudo-observations "discrete curvature = 0" at every interior vertex.
  kCurvature,
  // Pseudo-observations "discrete curvature = c", with c re-estimated from the
  // grey-value data after every iteration (block Gauss-Seidel between geometry and
  // curvature vector, seed 003): edges and ridges that the images show survive.
  kAdaptive,
  kNone,
};

enum class RadiometricModel {
  kNone,      // h0 = 0, h1 = 1 for every image
  kConstant,  // h0 per image, h1 = 1
  kLinear,    // h0 and h1 per image
};

Regularisation RegularisationFromName(const std::string& name);  // curvature|adaptive|none
RadiometricModel RadiometricModelFromName(const std::string& name);  // none|constant|linear
std::string RegularisationName(Regularisation r);
std::string RadiometricModelName(RadiometricModel m);

// Direction in which the vertices move: along their normals (3D: walls can
// stand up and overhang) or vertically only (a 2.5D height field, for comparison).
enum class Displacement { kNormal, kVertical };
Displacement DisplacementFromName(const std::string& name);  // normal|vertical

// Solver of one window's normal equations per iteration: sparse LDL^T (ordering and
// symbolic factorisation once per window run, numeric factorisation per iteration;
// the factor also gives the per-vertex sigma) or SSOR-preconditioned CG (`pcg`).
enum class WindowSolver { kLdlt, kPcg };
WindowSolver WindowSolverFromName(const std::string& name);  // ldlt|pcg
std::string WindowSolverName(WindowSolver s);

struct AdjustmentOptions {
  Regularisation regularisation = Regularisation::kCurvature;
  // Weight of one vertex's curvature pseudo-observation, in units of the pixel
  // observations one vertex gets from one image at the design resolution (a grey
  // facet covers 2x2 pixels, 16 facets per triangle, about 2 triangles per vertex:
  // 128 pixels of weight 1, residuals in grey values). The pseudo-observation is the
  // dimensionless discrete curvature  N_i . (mean of the 1-ring - X_i) / h_i  with
  // h_i the mean length of the vertex's edges. Because every level keeps the facet
  // at about 2x2 pixels, each vertex sees the same number of pixels on every level,
  // and the grey-value change per unit displacement scales like 1/h just as the
  // curvature does: lambda keeps its meaning across levels and facet sizes
  // (docs/ENGINE.md). The seeds' 1000-6000 land in the same range.
  double lambda = 1500.0;
  RadiometricModel radiometry = RadiometricModel::kNone;
  int reference_image = 0;  // index into the window's images; its h0 = 0, h1 = 1

  // Break-off: the iteration stops when the largest displacement (object units)
  // between two iterations falls below this bound for interior vertices, 2x for
  // border and 4x for corner vertices.
  double break_off = 0.01;
  int max_iterations = 30;
  // Stall stop: the iteration also ends (as stalled, not converged) when, over the last
  // stall_iterations iterations, sigma0 fell by less than stall_ratio (relative) and
  // the largest interior displacement did not shrink below 70 % and is still above 4x
  // break_off. A few vertices that
  // oscillate at a wall or ridge the level cannot represent would otherwise run every
  // window to max_iterations without changing the surface (the block scene: 60
  // iterations per window at sigma0 flat to 0.1 %). A converging run's displacements
  // shrink by about half per iteration, so it never stalls. 0 = off.
  int stall_iterations = 4;
  double stall_ratio = 0.003;
  // Largest displacement allowed in one iteration (object units); larger steps of
  // the linearised solution are scaled down so the surface stays valid. 0 = off.
  double max_step = 0.0;
  // Fold guard (mesh/surface_validity.h): a vertex step that would fold a triangle
  // against its neighbours or reverse its normal is halved, and undone if halving
  // does not help.
  bool fold_guard = true;
  Displacement displacement = Displacement::kNormal;

  // Edges whose two face normals differ by more than this are creases (ridges,
  // eaves, wall edges): the surface stays continuous but not smooth across them
  // (mesh/creases.h). 180 = a G1 surface everywhere.
  double crease_angle_deg = 20.0;
  // Also the middle row of a ridge rounded over a band of edge rows (mesh/creases.h):
  // curvature regularisation keeps a ridge round until it is a crease. Off for closed
  // starts, whose coarse facets bend by 10-20 degrees everywhere.
  bool rounded_ridges = true;

  // Rays at |cos incidence| below this are no observation.
  double min_cos_incidence = 0.1;

  // Background: pixels whose grey value (mean over the channels) is at or below this
  // give no observation, e.g. the black backdrop of an object photographed on a
  // turntable: untextured, it would pull the surface wherever the surface covers it.
  // Negative = off.
  double background_below = -1.0;
  // Robust weighting of gross residuals (pixels that fit no surface: background seen
  // past a silhouette, specular spots, moving things). Per iteration the robust scale
  // s = 1.4826 x median |residual| of the window's observations; a residual beyond
  // robust_k s gets the Huber weight robust_k s / |residual|, one beyond reject_k s is
  // rejected (no observation). 0 = off (each on its own).
  double robust_k = 0.0;
  double reject_k = 0.0;
  // Silhouette term (objects before a dark background): for every free vertex
  // on a rim of an image that has a silhouette (LevelImage::silhouette), i.e. seen
  // edge-on (|normal . ray| <= silhouette_rim_cos) and not hidden, one observation
  // "signed distance of the vertex's projection to the image's foreground outline = 0",
  // linearised along the vertex's direction: a rim projecting onto background pulls the
  // surface in, one inside the outline pushes it out. Only where the distance is within
  // silhouette_outside_px (on background) or silhouette_inside_px (inside; an interior
  // contour seen against the object itself lies deep inside) pixels of the level.
  // Weight: grey values^2 per level pixel^2 (a residual of one pixel counts as much as one
  // grey-value observation with a residual of sqrt(weight)). 0 = off.
  double silhouette_weight = 0.0;
  double silhouette_rim_cos = 0.3;
  double silhouette_outside_px = 6.0;
  double silhouette_inside_px = 1.5;
  // Tiny ridge on grey and radiometric unknowns (relative to the mean diagonal) so
  // nodes no pixel sees keep their value instead of making N singular.
  double grey_ridge = 1e-8;

  WindowSolver solver = WindowSolver::kLdlt;
  PcgOptions pcg;  // WindowSolver::kPcg, and the fallback when LDL^T finds N not positive definite
  // Compute per-vertex standard deviations at the end (sparse factorisation, one
  // solve per geometry unknown): meant for windows of a few hundred triangles; above
  // max_precision_unknowns unknowns it is skipped (WindowReport::precision_computed).
  bool compute_precision = true;
  // Per-vertex sigma accounts for the correlation of the residuals between neighbouring
  // pixels (image low-pass, resampling, unmodelled fine texture): the variance of dn is
  // multiplied by the factor sum over pixel lags of rho_v(lag) x rho_a(lag), rho_v the
  // residuals' and rho_a the displacement coefficients' autocorrelation (docs/ENGINE.md).
  bool correlated_residuals = true;
  // Measure that correlation at the end of a run (WindowReport::residual_rho_x/y and
  // variance_factor; one pass over every observation's pixel neighbours). Off where the
  // run's report only gives sigma0 (a trial's probes, the sweeps before a level's last):
  // rho 0 and variance factor 1 then.
  bool residual_correlation = true;
  int max_precision_unknowns = 60000;
  // A vertex is flagged undetermined when fewer images than this saw it, or its
  // standard deviation exceeds max_sigma (object units; 0 = no sigma test).
  int min_views = 2;
  // An image counts as a view of a vertex when it has at least this share of the best
  // image's pixels on the vertex's faces (0: any pixel; WindowAdjustment::VertexViews).
  double min_view_share = 0.3;
  double max_sigma = 0.0;

  // Not an option of the estimate: where each window run adds its phases' CPU seconds
  // (the run's profile); none when null.
  WindowClockSink* clocks = nullptr;

  // Throws std::invalid_argument naming the bad option.
  void Check() const;
};

}  // namespace facets
