#include "engine/solver/window_adjustment.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "engine/solver/window_adjustment_internal.h"
#include "mesh/creases.h"
#include "mesh/surface_validity.h"
#include "visibility/occluder_selection.h"
#include "visibility/surface_scene.h"

namespace facets {

using window_internal::FacetLocalNodes;
using window_internal::kLocal;
using window_internal::kNodesPerFace;
using window_internal::Seconds;

bool WindowAdjustment::Stalled(const std::vector<IterationReport>& iterations) const {
  const int k = options_.stall_iterations;
  const int n = static_cast<int>(iterations.size());
  if (k <= 0 || n <= k) return false;
  const IterationReport& then = iterations[n - 1 - k];
  const IterationReport& now = iterations[n - 1];
  const bool flat = then.sigma0 - now.sigma0 < options_.stall_ratio * then.sigma0;
  const bool not_shrinking = now.max_dn_interior >= 0.7 * then.max_dn_interior;
  // Steps within a few break-off bounds are noise around a solution that will
  // converge: only steps well above the bound count as a stall.
  const bool large = now.max_dn_interior > 4.0 * options_.break_off;
  return flat && not_shrinking && large;
}

std::string WindowReport::BriefReport() const {
  std::ostringstream out;
  out << (converged ? "converged" : stalled ? "stalled" : "NOT converged") << " after " << iterations.size()
      << " iterations, sigma0 " << sigma0 << " grey values, " << observations
      << " observations, " << unknowns << " unknowns, " << cg_iterations_total
      << " CG iterations, " << seconds_total << " s";
  return out.str();
}

WindowAdjustment::WindowAdjustment(TinMesh* mesh, std::vector<LevelImage> images,
                                   AdjustmentOptions options)
    : mesh_(mesh), images_(std::move(images)), options_(std::move(options)) {
  options_.Check();
  if (images_.empty()) throw std::invalid_argument("WindowAdjustment: no images");
  channels_ = images_.front().pixels->channels;
  for (const auto& image : images_) {
    if (!image.camera || !image.pixels) throw std::invalid_argument("WindowAdjustment: null image");
    if (image.pixels->channels != channels_) {
      throw std::invalid_argument("WindowAdjustment: image " + std::to_string(image.image_id) +
                                  " has " + std::to_string(image.pixels->channels) +
                                  " channels, expected " + std::to_string(channels_));
    }
    const ImagePlanes& p = *image.pixels;
    if (p.x0 < 0 || p.y0 < 0 || p.x0 + p.width > image.camera->width ||
        p.y0 + p.height > image.camera->height) {
      throw std::invalid_argument("WindowAdjustment: image " + std::to_string(image.image_id) +
                                  " pixels reach outside its camera's image");
    }
  }
  if (options_.reference_image >= static_cast<int>(images_.size())) {
    throw std::invalid_argument("WindowAdjustment: reference_image out of range");
  }
  fixed_.assign(mesh_->n_vertices(), false);
  radiometry_.assign(images_.size(), std::vector<std::array<double, 2>>(channels_, {0.0, 1.0}));
  curvature_target_.assign(mesh_->n_vertices(), 0.0);
}

WindowAdjustment::~WindowAdjustment() = default;

void WindowAdjustment::SetFixedVertices(std::vector<bool> fixed) {
  if (fixed.size() != mesh_->n_vertices()) {
    throw std::invalid_argument("SetFixedVertices: size differs from the vertex count");
  }
  fixed_ = std::move(fixed);
}

void WindowAdjustment::SetBreakOffVertices(std::vector<bool> judged) {
  if (judged.size() != mesh_->n_vertices()) {
    throw std::invalid_argument("SetBreakOffVertices: size differs from the vertex count");
  }
  judged_ = std::move(judged);
}

void WindowAdjustment::SetGreyValues(std::vector<double> grey) {
  grey_ = std::move(grey);
  grey_given_ = true;
}

void WindowAdjustment::SetOccluderSource(OccluderSource source) { occluder_source_ = std::move(source); }

Eigen::Vector3d WindowAdjustment::Direction(int v) const {
  if (options_.displacement == Displacement::kVertical) return Eigen::Vector3d::UnitZ();
  return ToEigen(mesh_->normal(mesh_->vertex_handle(v)));
}

void WindowAdjustment::BuildTopologyTables() {
  const int num_faces = static_cast<int>(mesh_->n_faces());
  face_vertices_.resize(num_faces);
  face_nodes_.resize(num_faces);
  const auto& local = FacetLocalNodes();
  for (int f = 0; f < num_faces; ++f) {
    int k = 0;
    for (auto vh : mesh_->fv_range(mesh_->face_handle(f))) face_vertices_[f][k++] = vh.idx();
    for (int s = 0; s < kSubTrianglesPerFace; ++s) {
      const Eigen::Vector3i& tri = tess_.triangles[f * kSubTrianglesPerFace + s];
      for (int c = 0; c < 3; ++c) face_nodes_[f][local[s][c]] = tri[c];
    }
  }
  const int num_vertices = static_cast<int>(mesh_->n_vertices());
  vertex_ring_.assign(num_vertices, {});
  vertex_class_.assign(num_vertices, 0);
  for (auto vh : mesh_->vertices()) {
    if (mesh_->is_boundary(vh)) {
      int faces = 0;
      for (auto fh : mesh_->vf_range(vh)) {
        (void)fh;
        ++faces;
      }
      vertex_class_[vh.idx()] = faces <= 2 ? 2 : 1;
    }
    // Border vertices get the one-sided umbrella: on a plane it is still zero, and
    // without it the half-observed border drifts from iteration to iteration.
    for (auto nh : mesh_->vv_range(vh)) vertex_ring_[vh.idx()].push_back(nh.idx());
  }
}

void WindowAdjustment::BuildPattern() {
  const int num_vertices = static_cast<int>(mesh_->n_vertices());
  vertex_unknown_.assign(num_vertices, -1);
  num_geometry_ = 0;
  for (int v = 0; v < num_vertices; ++v) {
    if (!fixed_[v]) vertex_unknown_[v] = num_geometry_++;
  }
  grey_offset_ = num_geometry_;
  const int num_nodes = static_cast<int>(tess_.points.size());
  rad_offset_ = grey_offset_ + num_nodes * channels_;
  num_rad_ = 0;
  rad_unknown_.assign(images_.size(), std::vector<std::array<int, 2>>(channels_, {-1, -1}));
  for (size_t k = 0; k < images_.size(); ++k) {
    if (static_cast<int>(k) == options_.reference_image) continue;
    for (int c = 0; c < channels_; ++c) {
      if (options_.radiometry != RadiometricModel::kNone) rad_unknown_[k][c][0] = rad_offset_ + num_rad_++;
      if (options_.radiometry == RadiometricModel::kLinear) rad_unknown_[k][c][1] = rad_offset_ + num_rad_++;
    }
  }
  num_unknowns_ = rad_offset_ + num_rad_;

  std::vector<std::vector<int>> cliques;
  const int num_faces = static_cast<int>(face_vertices_.size());
  cliques.reserve(static_cast<size_t>(num_faces) * channels_ + num_vertices);
  for (int f = 0; f < num_faces; ++f) {
    for (int c = 0; c < channels_; ++c) {
      std::vector<int> clique;
      for (int v : face_vertices_[f]) {
        if (vertex_unknown_[v] >= 0) clique.push_back(vertex_unknown_[v]);
      }
      for (int node : face_nodes_[f]) clique.push_back(grey_offset_ + node * channels_ + c);
      cliques.push_back(std::move(clique));
    }
  }
  for (int v = 0; v < num_vertices; ++v) {
    if (vertex_ring_[v].empty()) continue;
    std::vector<int> clique;
    if (vertex_unknown_[v] >= 0) clique.push_back(vertex_unknown_[v]);
    for (int n : vertex_ring_[v]) {
      if (vertex_unknown_[n] >= 0) clique.push_back(vertex_unknown_[n]);
    }
    if (!clique.empty()) cliques.push_back(std::move(clique));
  }
  if (num_rad_ > 0) {
    // Radiometric unknowns couple with everything an image sees; giving every row all
    // of them keeps them at the end of each row, at a computable slot.
    std::vector<int> rad(num_rad_);
    for (int r = 0; r < num_rad_; ++r) rad[r] = rad_offset_ + r;
    for (int u = 0; u < rad_offset_; ++u) {
      std::vector<int> clique = rad;
      clique.push_back(u);
      cliques.push_back(std::move(clique));
    }
    cliques.push_back(rad);
  }
  normal_ = CsrMatrix::FromCliques(num_unknowns_, cliques);

  slots_.assign(static_cast<size_t>(num_faces) * channels_ * kLocal * kLocal, -1);
  tbb::parallel_for(0, num_faces, [&](int f) {
    for (int c = 0; c < channels_; ++c) {
      std::array<int, kLocal> unknown;
      for (int i = 0; i < 3; ++i) unknown[i] = vertex_unknown_[face_vertices_[f][i]];
      for (int l = 0; l < kNodesPerFace; ++l) {
        unknown[3 + l] = grey_offset_ + face_nodes_[f][l] * channels_ + c;
      }
      int64_t* table = &slots_[(static_cast<size_t>(f) * channels_ + c) * kLocal * kLocal];
      for (int i = 0; i < kLocal; ++i) {
        for (int j = 0; j < kLocal; ++j) {
          if (unknown[i] >= 0 && unknown[j] >= 0) table[i * kLocal + j] = normal_.Find(unknown[i], unknown[j]);
        }
      }
    }
  });
}

WindowReport WindowAdjustment::Run() {
  const auto run_start = std::chrono::steady_clock::now();
  clocks_ = WindowClocks{};
  clocks_.runs = 1;
  double cpu = ThreadCpuSeconds();
  WindowReport report;
  PrepareRun(&report);
  clocks_.prepare = ThreadCpuLap(&cpu);
  std::vector<std::vector<PixelObservation>> casts;
  const double bounds[3] = {options_.break_off, 2 * options_.break_off, 4 * options_.break_off};
  for (int iteration = 1; iteration <= options_.max_iterations; ++iteration) {
    IterationReport it;
    it.iteration = iteration;
    ++clocks_.iterations;
    const Linearisation system = LineariseIteration(iteration, &casts, &it);
    cpu = ThreadCpuSeconds();
    const auto start = std::chrono::steady_clock::now();
    const Eigen::VectorXd solution = SolveNormalEquations(system.rhs, &it);
    rhs_ = system.rhs;
    it.seconds_solve = Seconds(start);
    clocks_.solve += ThreadCpuLap(&cpu);

    const long long redundancy = system.count + system.pseudo - system.determined;
    const double vpv = std::max(system.lpl - solution.dot(system.rhs), 0.0);
    it.sigma0 = redundancy > 0 ? std::sqrt(vpv / redundancy) : 0.0;
    it.rejected = rejected_;
    it.downweighted = downweighted_;
    report.observations = system.count;
    report.pseudo_observations = system.pseudo;
    report.background = it.background;
    report.rejected = rejected_;
    report.downweighted = downweighted_;
    report.silhouette = it.silhouette;
    report.silhouette_outside = it.silhouette_outside;
    report.unknowns = system.determined;
    report.redundancy = redundancy;

    const double scale = UpdateUnknowns(solution, &it);
    it.step_scale = scale;
    report.cg_iterations_total += it.cg_iterations;
    report.iterations.push_back(it);
    report.sigma0 = it.sigma0;
    if (scale == 1.0 && it.max_dn_interior < bounds[0] && it.max_dn_border < bounds[1] &&
        it.max_dn_corner < bounds[2]) {
      report.converged = true;
      break;
    }
    if (Stalled(report.iterations)) {
      report.stalled = true;
      break;
    }
  }
  cpu = ThreadCpuSeconds();
  FinishReport(casts, &report);
  clocks_.finish = ThreadCpuLap(&cpu);
  if (options_.clocks) options_.clocks->Add(clocks_);
  report.seconds_total = Seconds(run_start);
  return report;
}

void WindowAdjustment::PrepareRun(WindowReport* report) {
  // Creases are decided once per window run: the grey lattice (split along creases)
  // must keep its node indices while the adjustment iterates.
  crease_edges_ = DetectCreaseEdges(*mesh_, options_.crease_angle_deg, options_.rounded_ridges);
  {
    const CornerNormals corners = ComputeCornerNormals(*mesh_, crease_edges_);
    tess_ = Tessellate(*mesh_, BuildPatches(*mesh_, corners), corners);
    report->crease_edges = corners.num_crease_edges;
    crease_vertex_.assign(mesh_->n_vertices(), false);
    for (auto vh : mesh_->vertices()) crease_vertex_[vh.idx()] = corners.vertex_sectors[vh.idx()] > 1;
  }
  scene_ = std::make_unique<SurfaceScene>(tess_);
  occluders_.reset();  // asked for at the first cast
  BuildTopologyTables();
  BuildPattern();
  fold_crossings_ = {};  // the mesh may have changed since the last run
  if (options_.solver == WindowSolver::kLdlt) ldlt_.Analyze(normal_);
}

WindowAdjustment::Linearisation WindowAdjustment::LineariseIteration(
    int iteration, std::vector<std::vector<PixelObservation>>* casts, IterationReport* it) {
  double cpu = ThreadCpuSeconds();
  const std::vector<Eigen::AlignedBox3d> face_boxes = FaceBoxes(tess_);
  RefreshOccluders(face_boxes);
  clocks_.occluders += ThreadCpuLap(&cpu);
  auto start = std::chrono::steady_clock::now();
  it->observations = CastAll(face_boxes, casts, it);
  it->background = DropBackground(casts);
  it->observations -= it->background;
  it->seconds_cast = Seconds(start);
  clocks_.cast += ThreadCpuLap(&cpu);
  if (it->observations == 0) {
    throw std::runtime_error("WindowAdjustment: no image sees the window (0 observations)");
  }
  if (grey_.empty() || (iteration == 1 && !grey_given_)) InitialiseGrey(*casts);
  vertex_views_ = VertexViews(*casts);
  robust_scale_ = options_.robust_k > 0.0 || options_.reject_k > 0.0 ? RobustScale(*casts) : 0.0;
  it->robust_scale = robust_scale_;

  start = std::chrono::steady_clock::now();
  Linearisation system;
  system.lpl = Accumulate(*casts, &system.rhs, &system.count);
  system.lpl += AccumulateCurvature(&system.rhs, &system.pseudo);
  long long silhouette_outside = 0;
  system.lpl += AccumulateSilhouette(&system.rhs, &it->silhouette, &silhouette_outside);
  it->silhouette_outside = silhouette_outside;
  system.pseudo += it->silhouette;
  system.determined = AddRidge();
  it->seconds_linearise = Seconds(start);
  clocks_.linearise += ThreadCpuLap(&cpu);
  return system;
}

Eigen::VectorXd WindowAdjustment::SolveNormalEquations(const Eigen::VectorXd& rhs, IterationReport* it) {
  Eigen::VectorXd solution = Eigen::VectorXd::Zero(num_unknowns_);
  if (options_.solver == WindowSolver::kLdlt && ldlt_.Factorize(normal_)) {
    solution = ldlt_.Solve(rhs);
  } else {
    // PCG, also when LDL^T met a non-positive pivot (N numerically indefinite).
    const PcgSummary pcg = SolvePcg(normal_, rhs, options_.pcg, &solution);
    it->cg_iterations = pcg.iterations;
  }
  return solution;
}

double WindowAdjustment::UpdateUnknowns(const Eigen::VectorXd& solution, IterationReport* it) {
  // Vertices along their (current) normals, then grey values, radiometry.
  double cpu = ThreadCpuSeconds();
  const auto start = std::chrono::steady_clock::now();
  const int num_vertices = static_cast<int>(mesh_->n_vertices());
  double scale = 1.0;
  if (options_.max_step > 0.0) {
    double largest = 0.0;
    for (int v = 0; v < num_vertices; ++v) {
      if (vertex_unknown_[v] >= 0) largest = std::max(largest, std::abs(solution[vertex_unknown_[v]]));
    }
    if (largest > options_.max_step) scale = options_.max_step / largest;
  }
  double max_dn[3] = {0.0, 0.0, 0.0};
  std::vector<Eigen::Vector3d> before;  // for the fold guard
  if (options_.fold_guard) {
    for (auto vh : mesh_->vertices()) before.push_back(ToEigen(mesh_->point(vh)));
  }
  for (int v = 0; v < num_vertices; ++v) {
    if (vertex_unknown_[v] < 0) continue;
    const double dn = scale * solution[vertex_unknown_[v]];
    auto vh = mesh_->vertex_handle(v);
    mesh_->set_point(vh, mesh_->point(vh) + ToOpenMesh(dn * Direction(v)));
    if (judged_.empty() || judged_[v]) {
      max_dn[vertex_class_[v]] = std::max(max_dn[vertex_class_[v]], std::abs(dn));
    }
  }
  for (size_t n = 0; n < grey_.size(); ++n) grey_[n] += solution[grey_offset_ + n];
  for (size_t k = 0; k < images_.size(); ++k) {
    for (int c = 0; c < channels_; ++c) {
      if (rad_unknown_[k][c][0] >= 0) radiometry_[k][c][0] += solution[rad_unknown_[k][c][0]];
      if (rad_unknown_[k][c][1] >= 0) radiometry_[k][c][1] += solution[rad_unknown_[k][c][1]];
    }
  }
  if (options_.fold_guard) {
    it->fold_limited = LimitFoldingSteps(mesh_, before, kFoldGuardHalvings, &fold_crossings_);
  }
  UpdateVertexNormals(mesh_);
  if (options_.regularisation == Regularisation::kAdaptive) curvature_target_ = CurrentCurvatures();
  UpdateTessellationPoints(BuildPatches(*mesh_, ComputeCornerNormals(*mesh_, crease_edges_)), &tess_);
  scene_->Update(tess_);
  it->seconds_update = Seconds(start);
  clocks_.update += ThreadCpuLap(&cpu);
  it->max_dn_interior = max_dn[0];
  it->max_dn_border = max_dn[1];
  it->max_dn_corner = max_dn[2];
  return scale;
}

}  // namespace facets
