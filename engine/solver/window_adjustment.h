// Least-squares adjustment of one window on one pyramid level: multi-image matching
// in object space (DESIGN.md sections 4-6). Unknowns: normal displacements dn of the
// TIN vertices, object grey values at the grey nodes (per channel), radiometric
// transfer (h0, h1) per image and channel. Every visible pixel of every image is one
// observation; curvature pseudo-observations regularise the geometry.
//
// One iteration: update the G1 tessellation and its Embree scene, cast every pixel ray
// of every image (first hit only), linearise, assemble the normal equations straight
// into CSR, solve (sparse LDL^T, pattern analysed once per run; or SSOR-PCG), move the vertices along their normals and update grey
// values and radiometry; until the break-off criterion holds.
#pragma once

#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "engine/solver/adjustment_options.h"
#include "engine/solver/csr_matrix.h"
#include "engine/images/level_image.h"
#include "engine/solver/pcg.h"
#include "io/camera.h"
#include "io/image_io.h"
#include "io/rigid3d.h"
#include "mesh/surface_validity.h"
#include "mesh/tessellation.h"
#include "mesh/tin.h"
#include "visibility/embree_scene.h"
#include "visibility/pixel_cast.h"
#include "visibility/silhouette.h"

namespace facets {

struct FacetState;
struct PixelRay;

enum VertexFlag : uint8_t {
  kVertexOk = 0,
  kVertexFewViews = 1,     // seen by fewer than AdjustmentOptions::min_views images
  kVertexHighSigma = 2,    // standard deviation above AdjustmentOptions::max_sigma
  kVertexFixed = 4,        // held fixed (window border), not estimated here
};

struct IterationReport {
  int iteration = 0;
  long long observations = 0;
  long long rays = 0;  // pixel rays cast (the 8x8 blocks the window's faces project to)
  long long rect_pixels = 0;  // pixels of the window's rectangles in its images (cast without the blocks)
  int cg_iterations = 0;  // 0 when LDL^T solved the iteration
  double sigma0 = 0.0;           // of this linearisation, grey values
  // AdjustmentOptions::background_below / robust_k / reject_k: pixels dropped as
  // background, observations rejected and down-weighted, and the robust scale
  // (grey values) they were judged by.
  long long background = 0;
  long long rejected = 0;
  long long downweighted = 0;
  double robust_scale = 0.0;
  // AdjustmentOptions::silhouette_weight: rim observations, of them more than a level
  // pixel outside the outline (on background).
  long long silhouette = 0;
  long long silhouette_outside = 0;
  double max_dn_interior = 0.0;  // object units
  double max_dn_border = 0.0;
  double max_dn_corner = 0.0;
  int fold_limited = 0;  // vertices whose step the fold guard limited
  double step_scale = 1.0;  // factor the solution's steps were scaled by (AdjustmentOptions::max_step)
  double seconds_cast = 0.0;
  double seconds_linearise = 0.0;  // linearisation + accumulation into CSR
  double seconds_solve = 0.0;
  double seconds_update = 0.0;     // vertices, normals, tessellation, Embree scene
};

// Correlation of the residuals between neighbouring pixels of one image (lag 1 along x
// and y) and the variance factor of the vertex displacements it implies (>= 1).
struct CorrelatedResiduals {
  double rho_x = 0.0, rho_y = 0.0;
  double variance_factor = 1.0;
};

struct WindowReport {
  std::vector<IterationReport> iterations;
  bool converged = false;
  bool stalled = false;  // stopped by AdjustmentOptions::stall_iterations
  double sigma0 = 0.0;  // grey values, of the last linearisation
  long long observations = 0;
  long long pseudo_observations = 0;
  // Of the last iteration: background pixels, rejected and down-weighted observations
  // (rejected ones are not in `observations`).
  long long background = 0;
  long long rejected = 0;
  long long downweighted = 0;
  long long silhouette = 0;  // rim observations (AdjustmentOptions::silhouette_weight), last iteration
  long long silhouette_outside = 0;  // of them more than a level pixel outside the outline
  int unknowns = 0;
  long long redundancy = 0;
  int cg_iterations_total = 0;
  int crease_edges = 0;
  // Windows whose second run with the sharpened creases fitted worse and was dropped
  // (engine/pipeline/level_windows.cc); its iterations are not in `iterations`.
  int crease_passes_dropped = 0;
  int crease_pass_iterations_dropped = 0;
  double seconds_total = 0.0;
  double seconds_precision = 0.0;
  bool precision_computed = false;
  // Correlation of the residuals of neighbouring pixels (lag 1 along x, y) and the
  // variance factor applied to vertex_sigma (1 unless AdjustmentOptions::correlated_residuals).
  double residual_rho_x = 0.0, residual_rho_y = 0.0;
  double variance_factor = 1.0;
  // Per TIN vertex.
  std::vector<double> vertex_sigma;  // standard deviation of dn, object units (0: fixed)
  std::vector<int> vertex_views;     // images that saw the vertex's faces
  std::vector<uint8_t> vertex_flags;
  // Per image (index into the window's images) and channel: h0, h1.
  std::vector<std::vector<std::array<double, 2>>> radiometry;

  std::string BriefReport() const;
};

class WindowAdjustment {
 public:
  // The mesh is adjusted in place; its vertex normals must be set.
  WindowAdjustment(TinMesh* mesh, std::vector<LevelImage> images, AdjustmentOptions options);
  ~WindowAdjustment();

  // Vertices held fixed (e.g. window borders taken from neighbours); size = vertices.
  void SetFixedVertices(std::vector<bool> fixed);
  // Vertices whose displacements decide the break-off (size = vertices); default all
  // free ones. A window's margin is context only: its outer vertices, estimated
  // from few rings of faces, may keep moving while the core has converged.
  void SetBreakOffVertices(std::vector<bool> judged);
  // Grey values to start from (node-major: node * channels + c) instead of the mean
  // of the pixels that see each node.
  void SetGreyValues(std::vector<double> grey);

  // The surface around the window (e.g. the rest of the level's tessellated TIN): it
  // is no part of the window's unknowns, but a pixel whose ray hits it first sees
  // something else and is no observation of the window. Asked before every cast with
  // the bounding boxes of the window's faces as they stand (16 sub-triangles each, face
  // order): the source returns the occluders for that surface, the same scene while it
  // still serves (of the shared Embree device, EmbreeDevice::Shared()).
  using OccluderSource =
      std::function<std::shared_ptr<const OccluderScene>(const std::vector<Eigen::AlignedBox3d>& window_boxes)>;
  void SetOccluderSource(OccluderSource source);

  WindowReport Run();

  const Tessellation& tessellation() const { return tess_; }
  // The normal equations of the last iteration (with regularisation and ridge): for
  // solver comparisons and benchmarks.
  const CsrMatrix& normal_equations() const { return normal_; }
  const Eigen::VectorXd& right_hand_side() const { return rhs_; }
  int channels() const { return channels_; }
  // Object grey values per node: grey()[node * channels() + c].
  const std::vector<double>& grey() const { return grey_; }

 private:
  // One share of the sums of the normal equations (Accumulate): N's CSR values, the
  // right-hand side A'Pl, l'Pl and the counts of its observations.
  struct Share {
    std::vector<double> values;  // zero between iterations (ReduceShares clears it)
    Eigen::VectorXd rhs;
    double lpl = 0.0;
    long long count = 0;
    long long rejected = 0;
    long long downweighted = 0;
  };
  // The normal equations of one iteration as far as the solve and sigma0 need them.
  struct Linearisation {
    Eigen::VectorXd rhs;
    double lpl = 0.0;  // l'Pl of the observations and pseudo-observations
    long long count = 0;   // pixel observations
    long long pseudo = 0;  // curvature and silhouette pseudo-observations
    int determined = 0;    // unknowns determined beyond the ridge (AddRidge)
  };

  // AdjustmentOptions::stall_iterations: sigma0 flat and displacements not shrinking.
  bool Stalled(const std::vector<IterationReport>& iterations) const;
  // Creases, tessellation, Embree scene, topology tables and N's pattern of one Run.
  void PrepareRun(WindowReport* report);
  // Casts the pixels and assembles N (normal_) and the right-hand side.
  Linearisation LineariseIteration(int iteration, std::vector<std::vector<PixelObservation>>* casts,
                                   IterationReport* it);
  Eigen::VectorXd SolveNormalEquations(const Eigen::VectorXd& rhs, IterationReport* it);
  // Moves the vertices, grey values and radiometry by the solution; returns the factor
  // the steps were scaled by (AdjustmentOptions::max_step; 1 = unscaled).
  double UpdateUnknowns(const Eigen::VectorXd& solution, IterationReport* it);
  // Views, residual correlation, precision and flags of the last iteration.
  void FinishReport(const std::vector<std::vector<PixelObservation>>& casts, WindowReport* report);
  void ComputePrecision(const std::vector<std::vector<PixelObservation>>& casts, WindowReport* report);
  // Sigma of the vertices few images see from N without the pseudo-observations, where
  // that is larger than the formal one (q: diagonal of the full N^-1).
  void SigmaFromDataAlone(const std::vector<std::vector<PixelObservation>>& casts,
                          const std::vector<int>& few_view, const std::vector<int>& few_unknowns,
                          const Eigen::VectorXd& q, WindowReport* report);
  void BuildTopologyTables();
  void BuildPattern();
  // Returns the observations; *rays: how many pixel rays were cast.
  // The occluders for the window's faces as they stand (OccluderSource).
  void RefreshOccluders(const std::vector<Eigen::AlignedBox3d>& face_boxes);
  long long CastAll(const std::vector<Eigen::AlignedBox3d>& face_boxes,
                    std::vector<std::vector<PixelObservation>>* casts, IterationReport* it);
  void InitialiseGrey(const std::vector<std::vector<PixelObservation>>& casts);
  // Drops background pixels (AdjustmentOptions::background_below); returns how many.
  long long DropBackground(std::vector<std::vector<PixelObservation>>* casts) const;
  // 1.4826 x the median absolute residual at the current values (0: no observations).
  double RobustScale(const std::vector<std::vector<PixelObservation>>& casts) const;
  // Correlation of the last linearisation's residuals between neighbouring pixels of
  // the same image, and the variance factor they imply (AdjustmentOptions::correlated_residuals).
  static constexpr int kMaxCorrelationLag = 4;
  CorrelatedResiduals ResidualCorrelation(const std::vector<std::vector<PixelObservation>>& casts) const;
  // Linearises every pixel observation into N and *rhs; returns l'Pl.
  double Accumulate(const std::vector<std::vector<PixelObservation>>& casts,
                    Eigen::VectorXd* rhs, long long* count);
  // Image k's observations [first, last) into *share; terms: per observation, residual and
  // displacement coefficient summed over the channels.
  void AccumulateRun(size_t k, const PixelRays& rays, const std::vector<PixelObservation>& observations,
                     size_t first, size_t last, std::array<float, 2>* terms, Share* share) const;
  // Channel c of one observation; local: slots of its 6 unknowns among the face's 18.
  void AccumulatePixel(size_t k, int c, const PixelObservation& obs, const PixelRay& ray,
                       const FacetState& facet, const std::array<int, 6>& local,
                       std::array<float, 2>* term, Share* share) const;
  // The radiometric unknowns' rows and columns of one observation (weight w, residual l).
  void AccumulateRadiometry(const std::array<int, 2>& rad_unknown, const int unknown[6], const double a[6],
                            const double a_rad[2], double w, double l, Share* share) const;
  // Sums the shares, in their order, into N and *rhs; returns l'Pl.
  double ReduceShares(Eigen::VectorXd* rhs, long long* count);
  double AccumulateCurvature(Eigen::VectorXd* rhs, long long* count);
  // AdjustmentOptions::silhouette_weight: rim observations of the free vertices.
  double AccumulateSilhouette(Eigen::VectorXd* rhs, long long* count, long long* outside);
  // Adds the ridge to N's diagonal; returns the unknowns determined beyond it.
  int AddRidge();
  // Images with at least min_view_share of the best image's pixels on the faces around
  // each vertex.
  std::vector<int> VertexViews(const std::vector<std::vector<PixelObservation>>& casts) const;
  std::vector<double> CurrentCurvatures() const;
  // Unit direction vertex v moves in (AdjustmentOptions::displacement).
  Eigen::Vector3d Direction(int v) const;

  TinMesh* mesh_;
  std::vector<LevelImage> images_;
  AdjustmentOptions options_;
  int channels_ = 1;
  WindowClocks clocks_;  // of the current Run, added to options_.clocks at its end

  Tessellation tess_;
  std::unique_ptr<SurfaceScene> scene_;
  std::vector<double> grey_;
  bool grey_given_ = false;
  std::vector<std::vector<std::array<double, 2>>> radiometry_;  // [image][channel]
  std::vector<bool> fixed_;
  std::vector<bool> judged_;
  OccluderSource occluder_source_;
  std::shared_ptr<const OccluderScene> occluders_;  // attached to scene_
  std::vector<bool> crease_edges_;  // by edge, fixed for one Run
  std::vector<bool> crease_vertex_;  // vertices where creases separate face sectors
  std::vector<int> vertex_views_;    // VertexViews of the current iteration
  std::vector<double> curvature_target_;  // adaptive regularisation, per vertex
  // Robust weighting of the current iteration (0 = off) and what it did.
  double robust_scale_ = 0.0;
  // Per image and observation of the last Accumulate: residual, displacement coefficient.
  std::vector<std::vector<std::array<float, 2>>> obs_terms_;
  // Accumulate's shares, kept across iterations: fresh nnz-sized buffers every
  // iteration cost more in page faults than the sums themselves.
  std::vector<Share> shares_;
  // The fold guard's crossing pairs of the current points, when its last test saw them.
  KnownCrossings fold_crossings_;
  long long rejected_ = 0;
  long long downweighted_ = 0;

  // Topology tables (fixed for one adjustment).
  std::vector<std::array<int, 3>> face_vertices_;
  std::vector<std::array<int, 15>> face_nodes_;  // lattice node of face-local node l
  std::vector<std::vector<int>> vertex_ring_;    // 1-ring (one-sided at the border)
  std::vector<uint8_t> vertex_class_;            // 0 interior, 1 border, 2 corner

  // Unknown layout: [vertex dn | node grey (node * C + c) | radiometry].
  std::vector<int> vertex_unknown_;  // -1 when fixed
  int num_geometry_ = 0;
  int grey_offset_ = 0;
  int rad_offset_ = 0;
  int num_rad_ = 0;
  std::vector<std::vector<std::array<int, 2>>> rad_unknown_;  // [image][channel] -> h0, h1 (-1)
  int num_unknowns_ = 0;
  CsrMatrix normal_;
  Eigen::VectorXd rhs_;
  SparseLdlt ldlt_;  // WindowSolver::kLdlt: analysed once per Run, factorised per iteration
  // Per face and channel, CSR slots of the 18 face-local unknowns (3 vertices then 15
  // nodes of that channel): slots_[(f * C + c) * 324 + 18 * i + j], -1 if fixed.
  std::vector<int64_t> slots_;
};

}  // namespace facets
