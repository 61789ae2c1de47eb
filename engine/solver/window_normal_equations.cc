// WindowAdjustment: the normal equations of one iteration (DESIGN.md section 4). The
// pixel observations are linearised and summed straight into N's CSR slots in a fixed
// number of shares; then the curvature and silhouette pseudo-observations and the ridge
// are added.
#include "engine/solver/window_adjustment.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "engine/solver/observation.h"
#include "engine/solver/window_adjustment_internal.h"
#include "visibility/surface_scene.h"

namespace facets {

using window_internal::FacetLocalNodes;
using window_internal::kLocal;

double WindowAdjustment::Accumulate(const std::vector<std::vector<PixelObservation>>& casts,
                                    Eigen::VectorXd* rhs, long long* count) {
  const int64_t nnz = normal_.nonZeros();
  // A fixed number of shares, each summing fixed runs of every image's observations in
  // their order, then added up in share order: the same sums, to the last bit, whatever
  // the number of threads and however TBB schedules them (thread-local shares made runs
  // differ in the last digits, and iterations, stall stops and fold-guard decisions
  // amplify that into visibly different surfaces).
  constexpr int kShares = 8;
  // The values stay allocated and zero between iterations (ReduceShares clears what it
  // has added), so only a changed pattern allocates.
  shares_.resize(kShares);
  for (Share& p : shares_) {
    if (static_cast<int64_t>(p.values.size()) != nnz) p.values.assign(nnz, 0.0);
    p.rhs.setZero(num_unknowns_);
    p.lpl = 0.0;
    p.count = p.rejected = p.downweighted = 0;
  }
  obs_terms_.resize(casts.size());
  for (size_t k = 0; k < casts.size(); ++k) {
    const auto& observations = casts[k];
    obs_terms_[k].clear();
    if (observations.empty()) continue;
    // Residual and grey-value change per unit displacement of the face, summed over
    // the channels; NaN: no observation (ResidualCorrelation).
    obs_terms_[k].assign(observations.size(), {std::numeric_limits<float>::quiet_NaN(), 0.0f});
    std::array<float, 2>* terms = obs_terms_[k].data();
    const PixelRays rays(*images_[k].camera, images_[k].cam_from_world);
    const size_t run = (observations.size() + kShares - 1) / kShares;
    tbb::parallel_for(0, kShares, [&](int share) {
      const size_t first = std::min(observations.size(), share * run);
      const size_t last = std::min(observations.size(), first + run);
      AccumulateRun(k, rays, observations, first, last, terms, &shares_[share]);
    });
  }
  return ReduceShares(rhs, count);
}

void WindowAdjustment::AccumulateRun(size_t k, const PixelRays& rays,
                                     const std::vector<PixelObservation>& observations, size_t first,
                                     size_t last, std::array<float, 2>* terms, Share* share) const {
  const auto& local_nodes = FacetLocalNodes();
  PixelRay ray;
  ray.origin = rays.origin();
  FacetState facet;
  for (size_t o = first; o != last; ++o) {
    const PixelObservation& obs = observations[o];
    const int f = obs.face;
    const int local_k = obs.facet % kSubTrianglesPerFace;
    const Eigen::Vector3i& tri = tess_.triangles[obs.facet];
    const auto& corners = SubTriangleCorners(local_k);
    for (int j = 0; j < 3; ++j) {
      facet.corners[j] = tess_.points[tri[j]];
      facet.corner_face_barycentric[j] = corners[j];
      facet.vertex_normals[j] = Direction(face_vertices_[f][j]);
    }
    ray.direction = rays.Direction(obs.x, obs.y);
    // Slots of the observation's 6 unknowns among the face's kLocal: the 3 vertices,
    // then the facet's 3 grey nodes.
    std::array<int, 6> local;
    for (int i = 0; i < 3; ++i) local[i] = i;
    for (int i = 0; i < 3; ++i) local[3 + i] = 3 + local_nodes[local_k][i];
    for (int c = 0; c < channels_; ++c) {
      for (int j = 0; j < 3; ++j) facet.grey[j] = grey_[tri[j] * channels_ + c];
      AccumulatePixel(k, c, obs, ray, facet, local, &terms[o], share);
    }
  }
}

void WindowAdjustment::AccumulatePixel(size_t k, int c, const PixelObservation& obs, const PixelRay& ray,
                                       const FacetState& facet, const std::array<int, 6>& local,
                                       std::array<float, 2>* term, Share* p) const {
  const int f = obs.face;
  const Eigen::Vector3i& tri = tess_.triangles[obs.facet];
  const auto& rad = radiometry_[k][c];
  const ObservationCoefficients lin = Linearise(ray, facet, obs.u, obs.v, Radiometry{rad[0], rad[1]});
  if (!lin.valid) return;
  const double g = images_[k].pixels->at(c, obs.x, obs.y);
  const double l = g - lin.predicted;
  // Robust weight (AdjustmentOptions::robust_k, reject_k): w scales the
  // observation's row, so the normal equations get w a a' and w a l.
  double w = 1.0;
  if (robust_scale_ > 0.0) {
    const double ratio = std::abs(l) / robust_scale_;
    if (options_.reject_k > 0.0 && ratio > options_.reject_k) {
      ++p->rejected;
      return;
    }
    if (options_.robust_k > 0.0 && ratio > options_.robust_k) {
      w = options_.robust_k / ratio;
      ++p->downweighted;
    }
  }
  const double a[6] = {lin.dn[0], lin.dn[1], lin.dn[2], lin.grey[0], lin.grey[1], lin.grey[2]};
  (*term)[0] = (std::isnan((*term)[0]) ? 0.0f : (*term)[0]) + static_cast<float>(l);
  (*term)[1] += static_cast<float>(a[0] + a[1] + a[2]);
  const int64_t* table = &slots_[(static_cast<size_t>(f) * channels_ + c) * kLocal * kLocal];
  int unknown[6];
  for (int i = 0; i < 3; ++i) unknown[i] = vertex_unknown_[face_vertices_[f][i]];
  for (int i = 0; i < 3; ++i) unknown[3 + i] = grey_offset_ + tri[i] * channels_ + c;
  for (int i = 0; i < 6; ++i) {
    if (unknown[i] < 0) continue;
    p->rhs[unknown[i]] += w * a[i] * l;
    const int64_t* row = table + local[i] * kLocal;
    for (int j = 0; j < 6; ++j) {
      const int64_t slot = row[local[j]];
      if (slot >= 0) p->values[slot] += w * a[i] * a[j];
    }
  }
  const double a_rad[2] = {lin.h0, lin.h1};
  AccumulateRadiometry(rad_unknown_[k][c], unknown, a, a_rad, w, l, p);
  p->lpl += w * l * l;
  ++p->count;
}

void WindowAdjustment::AccumulateRadiometry(const std::array<int, 2>& rad_unknown, const int unknown[6],
                                            const double a[6], const double a_rad[2], double w, double l,
                                            Share* p) const {
  const auto& row_ptr = normal_.row_ptr();
  for (int r = 0; r < 2; ++r) {
    const int ur = rad_unknown[r];
    if (ur < 0) continue;
    p->rhs[ur] += w * a_rad[r] * l;
    // Every row holds all radiometric unknowns at its end (BuildPattern).
    const int64_t rad_col = ur - rad_offset_;
    for (int i = 0; i < 6; ++i) {
      if (unknown[i] < 0) continue;
      const double product = w * a[i] * a_rad[r];
      p->values[row_ptr[unknown[i] + 1] - num_rad_ + rad_col] += product;
      p->values[row_ptr[ur] + unknown[i]] += product;
    }
    for (int s = 0; s < 2; ++s) {
      if (rad_unknown[s] >= 0) p->values[row_ptr[ur] + rad_unknown[s]] += w * a_rad[r] * a_rad[s];
    }
  }
}

double WindowAdjustment::ReduceShares(Eigen::VectorXd* rhs, long long* count) {
  const int64_t nnz = normal_.nonZeros();
  std::vector<double>& values = normal_.values();
  std::fill(values.begin(), values.end(), 0.0);
  *rhs = Eigen::VectorXd::Zero(num_unknowns_);
  double lpl = 0.0;
  *count = 0;
  rejected_ = 0;
  downweighted_ = 0;
  for (Share& p : shares_) {
    rejected_ += p.rejected;
    downweighted_ += p.downweighted;
    tbb::parallel_for(tbb::blocked_range<int64_t>(0, nnz, 1 << 16),
                      [&](const tbb::blocked_range<int64_t>& range) {
      for (int64_t i = range.begin(); i != range.end(); ++i) {
        values[i] += p.values[i];
        p.values[i] = 0.0;  // ready for the next Accumulate
      }
    });
    *rhs += p.rhs;
    lpl += p.lpl;
    *count += p.count;
  }
  return lpl;
}

namespace {

// The mean of a vertex's ring and the mean length of its edges to it (object units).
void RingMean(const TinMesh& mesh, const Eigen::Vector3d& x, const std::vector<int>& ring, Eigen::Vector3d* mean,
              double* h) {
  *mean = Eigen::Vector3d::Zero();
  *h = 0.0;
  for (int j : ring) {
    const Eigen::Vector3d xj = ToEigen(mesh.point(mesh.vertex_handle(j)));
    *mean += xj;
    *h += (xj - x).norm();
  }
  *mean /= ring.size();
  *h /= ring.size();
}

}  // namespace

std::vector<double> WindowAdjustment::CurrentCurvatures() const {
  std::vector<double> curvature(mesh_->n_vertices(), 0.0);
  for (size_t v = 0; v < vertex_ring_.size(); ++v) {
    const auto& ring = vertex_ring_[v];
    if (ring.empty()) continue;
    const Eigen::Vector3d x = ToEigen(mesh_->point(mesh_->vertex_handle(static_cast<int>(v))));
    const Eigen::Vector3d n = ToEigen(mesh_->normal(mesh_->vertex_handle(static_cast<int>(v))));
    Eigen::Vector3d mean;
    double h = 0.0;
    RingMean(*mesh_, x, ring, &mean, &h);
    curvature[v] = n.dot(mean - x) / h;
  }
  return curvature;
}

double WindowAdjustment::AccumulateCurvature(Eigen::VectorXd* rhs, long long* count) {
  if (options_.regularisation == Regularisation::kNone || options_.lambda == 0.0) return 0.0;
  // Pixel observations one vertex gets from one image at the design resolution:
  // 2 triangles x 16 grey facets x 2x2 pixels (see AdjustmentOptions::lambda).
  constexpr double kPixelsPerVertex = 2 * kSubTrianglesPerFace * 4;
  const double weight = options_.lambda * kPixelsPerVertex;
  double lpl = 0.0;
  for (size_t v = 0; v < vertex_ring_.size(); ++v) {
    const auto& ring = vertex_ring_[v];
    if (ring.empty()) continue;
    // Creases are meant to bend, where images say so: a crease vertex fewer than
    // min_views images see (a wall's foot behind a building, an eave seen once) has no
    // data to determine it and keeps its curvature pseudo-observation, else it is
    // held by nothing but the ridge and its sigma says it is arbitrary.
    if (crease_vertex_[v] && vertex_views_[v] >= options_.min_views) continue;
    const double target =
        options_.regularisation == Regularisation::kAdaptive ? curvature_target_[v] : 0.0;
    // One pseudo-observation "n . (mean of the ring - x) / h = target" for vertex v.
    const Eigen::Vector3d n = ToEigen(mesh_->normal(mesh_->vertex_handle(static_cast<int>(v))));
    const Eigen::Vector3d x = ToEigen(mesh_->point(mesh_->vertex_handle(static_cast<int>(v))));
    Eigen::Vector3d mean;
    double h = 0.0;
    RingMean(*mesh_, x, ring, &mean, &h);
    std::vector<std::pair<int, double>> terms;
    if (vertex_unknown_[v] >= 0) terms.emplace_back(vertex_unknown_[v], -n.dot(Direction(static_cast<int>(v))) / h);
    for (int j : ring) {
      if (vertex_unknown_[j] < 0) continue;
      terms.emplace_back(vertex_unknown_[j], n.dot(Direction(j)) / (ring.size() * h));
    }
    if (terms.empty()) continue;
    const double l = target - n.dot(mean - x) / h;
    for (const auto& [ui, ai] : terms) {
      (*rhs)[ui] += weight * ai * l;
      for (const auto& [uj, aj] : terms) normal_.Add(ui, uj, weight * ai * aj);
    }
    lpl += weight * l * l;
    ++*count;
  }
  return lpl;
}

double WindowAdjustment::AccumulateSilhouette(Eigen::VectorXd* rhs, long long* count, long long* outside) {
  *count = 0;
  *outside = 0;
  if (options_.silhouette_weight <= 0.0) return 0.0;
  const double weight = options_.silhouette_weight;
  const int num_vertices = static_cast<int>(mesh_->n_vertices());
  double lpl = 0.0;
  for (const LevelImage& image : images_) {
    const SilhouetteView* view = image.silhouette;
    if (!view) continue;
    const Eigen::Vector3d centre = view->cam_from_world.Inverse().translation;
    // Level pixels -> pixels of the silhouette's (full-size) image.
    const double to_full = view->camera.FocalX() / image.camera->FocalX();
    const double max_out = options_.silhouette_outside_px * to_full;
    const double max_in = options_.silhouette_inside_px * to_full;
    // The observation is written in level pixels: the weight means the same on every level.
    const double per_level_pixel = 1.0 / to_full;
    for (int v = 0; v < num_vertices; ++v) {
      const int u = vertex_unknown_[v];
      if (u < 0 || vertex_ring_[v].empty()) continue;
      auto vh = mesh_->vertex_handle(v);
      const Eigen::Vector3d x = ToEigen(mesh_->point(vh));
      const Eigen::Vector3d n = Direction(v);
      const Eigen::Vector3d ray = x - centre;
      const double depth = ray.norm();
      if (!(depth > 0.0) || std::abs(n.dot(ray)) > options_.silhouette_rim_cos * depth) continue;
      const Eigen::Vector3d in_cam = view->cam_from_world * x;
      if (in_cam.z() <= 0.0) continue;
      const Eigen::Vector2d p = view->camera.ImageFromCam(in_cam);
      double s = 0.0;
      Eigen::Vector2d gradient;
      if (!view->distance.Sample(p, &s, &gradient)) continue;
      if (s > max_out || s < -max_in) continue;
      // Pixels the projection moves per unit displacement along the direction, and how
      // much of it goes across the outline.
      const double eps = 1e-4 * depth;
      const Eigen::Vector3d moved = view->cam_from_world * (x + eps * n);
      if (moved.z() <= 0.0) continue;
      const Eigen::Vector2d shift = (view->camera.ImageFromCam(moved) - p) / eps;
      const double a_full = gradient.dot(shift);
      if (!(a_full > 0.5 * shift.norm() * gradient.norm()) || gradient.norm() < 0.5) continue;
      // Hidden by the surface itself or its surroundings (an interior contour behind a
      // column): not this image's outline. The grazing ray may touch the ring's facets.
      double h = 0.0;
      for (int j : vertex_ring_[v]) h += (ToEigen(mesh_->point(mesh_->vertex_handle(j))) - x).norm();
      h /= vertex_ring_[v].size();
      const float t_far = static_cast<float>(depth - 0.5 * h);
      if (t_far > 0.0f && scene_->triangle_scene().Intersect(centre, ray / depth, 0.0f, t_far).hit) continue;
      const double a = a_full * per_level_pixel;
      const double l = -s * per_level_pixel;
      (*rhs)[u] += weight * a * l;
      normal_.Add(u, u, weight * a * a);
      lpl += weight * l * l;
      ++*count;
      if (s > to_full) ++*outside;  // more than a level pixel outside
    }
  }
  return lpl;
}

int WindowAdjustment::AddRidge() {
  // Ridge: keeps unknowns without any observation (grey nodes nobody sees, vertices
  // outside every view) at their value instead of making N singular.
  double mean_diag = 0.0;
  for (int i = 0; i < num_unknowns_; ++i) mean_diag += normal_.Diagonal(i);
  mean_diag = std::max(mean_diag / std::max(num_unknowns_, 1), 1e-300);
  int determined = 0;
  for (int i = 0; i < num_unknowns_; ++i) {
    const int64_t slot = normal_.diagonal_index()[i];
    if (normal_.values()[slot] > options_.grey_ridge * mean_diag) ++determined;
    normal_.values()[slot] += options_.grey_ridge * mean_diag;
  }
  return determined;
}

}  // namespace facets
