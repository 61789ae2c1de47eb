#include "engine/solver/window_adjustment.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <unordered_map>

#include "engine/solver/observation.h"
#include "mesh/creases.h"
#include "mesh/surface_validity.h"
#include "visibility/image_selection.h"
#include "visibility/occluder_selection.h"
#include "visibility/surface_scene.h"

namespace facets {
namespace {

constexpr int kNodesPerFace = 15;
constexpr int kLocal = 3 + kNodesPerFace;  // face-local unknowns per channel

double Seconds(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// Face-local id of lattice node (i, j), i + j <= 4, counted row by row.
int LocalNodeId(int i, int j) { return 5 * j - j * (j - 1) / 2 + i; }

// For each local sub-triangle k, the face-local node ids of its three corners.
const std::array<std::array<int, 3>, kSubTrianglesPerFace>& FacetLocalNodes() {
  static const auto table = [] {
    std::array<std::array<int, 3>, kSubTrianglesPerFace> t;
    for (int k = 0; k < kSubTrianglesPerFace; ++k) {
      const auto& corners = SubTriangleCorners(k);
      for (int c = 0; c < 3; ++c) {
        const int i = static_cast<int>(std::lround(corners[c][1] * kSubdivisions));
        const int j = static_cast<int>(std::lround(corners[c][2] * kSubdivisions));
        t[k][c] = LocalNodeId(i, j);
      }
    }
    return t;
  }();
  return table;
}

// Thread-local share of the normal equations.
struct Partial {
  std::vector<double> values;
  Eigen::VectorXd rhs;
  double lpl = 0.0;
  long long count = 0;
  long long rejected = 0;
  long long downweighted = 0;
};

}  // namespace

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

long long WindowAdjustment::CastAll(std::vector<std::vector<PixelObservation>>* casts, IterationReport* it) {
  Eigen::AlignedBox3d box;
  for (const auto& p : tess_.points) box.extend(p);
  // Only the 8x8 pixel blocks onto which some face of the window projects: the rest of
  // the window's rectangle sees the surroundings only.
  const std::vector<Eigen::AlignedBox3d> face_boxes = FaceBoxes(tess_);
  CastOptions cast_options;
  cast_options.min_cos_incidence = options_.min_cos_incidence;
  casts->assign(images_.size(), {});
  std::vector<long long> image_rays(images_.size(), 0), image_rect(images_.size(), 0);
  tbb::parallel_for(size_t{0}, images_.size(), [&](size_t k) {
    const auto rect = ProjectBox(box, *images_[k].camera, images_[k].cam_from_world);
    if (!rect) return;
    // Only pixels the window was given (a region of the image when read per window).
    const ImagePlanes& pixels = *images_[k].pixels;
    const PixelRect held{pixels.x0, pixels.y0, pixels.x0 + pixels.width, pixels.y0 + pixels.height};
    const PixelRect cast = rect->Intersection(held);
    if (cast.Empty()) return;
    image_rect[k] = cast.Area();
    const std::vector<PixelRect> blocks =
        ProjectedBlocks(face_boxes, *images_[k].camera, images_[k].cam_from_world, cast);
    CastResult result = CastPixels(*scene_, *images_[k].camera, images_[k].cam_from_world, blocks, cast_options);
    image_rays[k] = result.stats.rays;
    (*casts)[k] = std::move(result.observations);
  });
  it->rays = it->rect_pixels = 0;
  for (size_t k = 0; k < images_.size(); ++k) {
    it->rays += image_rays[k];
    it->rect_pixels += image_rect[k];
  }
  long long total = 0;
  for (const auto& list : *casts) total += static_cast<long long>(list.size());
  return total;
}

long long WindowAdjustment::DropBackground(std::vector<std::vector<PixelObservation>>* casts) const {
  if (options_.background_below < 0.0) return 0;
  long long dropped = 0;
  for (size_t k = 0; k < casts->size(); ++k) {
    const ImagePlanes& pixels = *images_[k].pixels;
    auto& list = (*casts)[k];
    const size_t before = list.size();
    list.erase(std::remove_if(list.begin(), list.end(),
                              [&](const PixelObservation& obs) {
                                double sum = 0.0;
                                for (int c = 0; c < channels_; ++c) sum += pixels.at(c, obs.x, obs.y);
                                return sum / channels_ <= options_.background_below;
                              }),
               list.end());
    dropped += static_cast<long long>(before - list.size());
  }
  return dropped;
}

double WindowAdjustment::RobustScale(const std::vector<std::vector<PixelObservation>>& casts) const {
  std::vector<float> residuals;
  for (size_t k = 0; k < casts.size(); ++k) {
    const ImagePlanes& pixels = *images_[k].pixels;
    for (const PixelObservation& obs : casts[k]) {
      const Eigen::Vector3i& tri = tess_.triangles[obs.facet];
      for (int c = 0; c < channels_; ++c) {
        const double object = (1.0 - obs.u - obs.v) * grey_[tri[0] * channels_ + c] +
                              obs.u * grey_[tri[1] * channels_ + c] + obs.v * grey_[tri[2] * channels_ + c];
        const auto& rad = radiometry_[k][c];
        const double predicted = (object - rad[0]) / rad[1];
        residuals.push_back(static_cast<float>(std::abs(pixels.at(c, obs.x, obs.y) - predicted)));
      }
    }
  }
  if (residuals.empty()) return 0.0;
  auto middle = residuals.begin() + residuals.size() / 2;
  std::nth_element(residuals.begin(), middle, residuals.end());
  return 1.4826 * *middle;
}

CorrelatedResiduals WindowAdjustment::ResidualCorrelation(
    const std::vector<std::vector<PixelObservation>>& casts) const {
  constexpr int L = kMaxCorrelationLag;
  constexpr int kSide = 2 * L + 1;
  const size_t num_lags = static_cast<size_t>(kSide) * (L + 1);
  // Pooled sums over pixel pairs (p, p + lag) of one image, lag in the upper half-plane:
  // for the residuals v and the displacement coefficients a.
  std::vector<double> svv(num_lags, 0.0), sv1(num_lags, 0.0), sv2(num_lags, 0.0);
  std::vector<double> saa(num_lags, 0.0), sa1(num_lags, 0.0), sa2(num_lags, 0.0);
  for (size_t k = 0; k < casts.size() && k < obs_terms_.size(); ++k) {
    const auto& obs = casts[k];
    const auto& terms = obs_terms_[k];
    if (obs.empty() || terms.size() != obs.size()) continue;
    int x0 = obs[0].x, x1 = x0, y0 = obs[0].y, y1 = y0;
    for (const PixelObservation& o : obs) {
      x0 = std::min(x0, o.x); x1 = std::max(x1, o.x);
      y0 = std::min(y0, o.y); y1 = std::max(y1, o.y);
    }
    // Pixel -> observation: a dense index over the observations' bounding box, or a hash
    // map when the box is much larger than the observations (e.g. a window seen twice far
    // apart in one large image), so the memory stays bounded by the observations.
    const int64_t w = x1 - x0 + 1, h = y1 - y0 + 1;
    const bool dense = w * h <= 8 * static_cast<int64_t>(obs.size()) + (int64_t{1} << 20);
    std::vector<int32_t> grid;
    std::unordered_map<int64_t, int32_t> sparse;
    if (dense) {
      grid.assign(static_cast<size_t>(w * h), -1);
    } else {
      sparse.reserve(obs.size());
    }
    for (size_t o = 0; o < obs.size(); ++o) {
      if (std::isnan(terms[o][0])) continue;
      const int64_t key = (obs[o].y - y0) * w + (obs[o].x - x0);
      if (dense) grid[static_cast<size_t>(key)] = static_cast<int32_t>(o);
      else sparse[key] = static_cast<int32_t>(o);
    }
    auto find = [&](int64_t x, int64_t y) -> int32_t {
      if (x < 0 || x >= w || y < 0 || y >= h) return -1;
      const int64_t key = y * w + x;
      if (dense) return grid[static_cast<size_t>(key)];
      const auto it = sparse.find(key);
      return it == sparse.end() ? -1 : it->second;
    };
    for (size_t o = 0; o < obs.size(); ++o) {
      const auto& p = terms[o];
      if (std::isnan(p[0])) continue;
      const int64_t x = obs[o].x - x0, y = obs[o].y - y0;
      for (int dy = 0; dy <= L; ++dy) {
        for (int dx = dy == 0 ? 0 : -L; dx <= L; ++dx) {
          const int32_t other = find(x + dx, y + dy);
          if (other < 0) continue;
          const auto& q = terms[static_cast<size_t>(other)];
          const size_t lag = static_cast<size_t>(dy) * kSide + dx + L;
          svv[lag] += double(p[0]) * q[0]; sv1[lag] += double(p[0]) * p[0]; sv2[lag] += double(q[0]) * q[0];
          saa[lag] += double(p[1]) * q[1]; sa1[lag] += double(p[1]) * p[1]; sa2[lag] += double(q[1]) * q[1];
        }
      }
    }
  }
  CorrelatedResiduals c;
  auto corr = [](double ab, double aa, double bb) { return aa > 0.0 && bb > 0.0 ? ab / std::sqrt(aa * bb) : 0.0; };
  c.rho_x = corr(svv[L + 1], sv1[L + 1], sv2[L + 1]);
  c.rho_y = corr(svv[kSide + L], sv1[kSide + L], sv2[kSide + L]);
  // Variance of a weighted sum sum_p a_p v_p of a stationary field v relative to white
  // v: sum over lags of rho_v(lag) rho_a(lag) (both lag and -lag; lag 0 counts once).
  double factor = 1.0;
  for (int dy = 0; dy <= L; ++dy) {
    for (int dx = dy == 0 ? 1 : -L; dx <= L; ++dx) {
      const size_t lag = static_cast<size_t>(dy) * kSide + dx + L;
      factor += 2.0 * corr(svv[lag], sv1[lag], sv2[lag]) * corr(saa[lag], sa1[lag], sa2[lag]);
    }
  }
  c.variance_factor = std::max(factor, 1.0);
  return c;
}

void WindowAdjustment::InitialiseGrey(const std::vector<std::vector<PixelObservation>>& casts) {
  const size_t num_nodes = tess_.points.size();
  std::vector<double> sum(num_nodes * channels_, 0.0), weight(num_nodes, 0.0);
  double total = 0.0;
  long long count = 0;
  for (size_t k = 0; k < casts.size(); ++k) {
    const ImagePlanes& pixels = *images_[k].pixels;
    for (const PixelObservation& obs : casts[k]) {
      const Eigen::Vector3i& tri = tess_.triangles[obs.facet];
      const double w[3] = {1.0 - obs.u - obs.v, obs.u, obs.v};
      for (int corner = 0; corner < 3; ++corner) {
        weight[tri[corner]] += w[corner];
        for (int c = 0; c < channels_; ++c) {
          const double g = pixels.at(c, obs.x, obs.y);
          const auto& rad = radiometry_[k][c];
          sum[tri[corner] * channels_ + c] += w[corner] * (g * rad[1] + rad[0]);
        }
      }
      for (int c = 0; c < channels_; ++c) {
        total += pixels.at(c, obs.x, obs.y);
      }
      ++count;
    }
  }
  const double mean = count > 0 ? total / (count * channels_) : 0.0;
  grey_.assign(num_nodes * channels_, mean);
  for (size_t n = 0; n < num_nodes; ++n) {
    if (weight[n] <= 1e-9) continue;
    for (int c = 0; c < channels_; ++c) grey_[n * channels_ + c] = sum[n * channels_ + c] / weight[n];
  }
}

double WindowAdjustment::Accumulate(const std::vector<std::vector<PixelObservation>>& casts,
                                    Eigen::VectorXd* rhs, long long* count) {
  const auto& row_ptr = normal_.row_ptr();
  const int64_t nnz = normal_.nonZeros();
  const auto& local_nodes = FacetLocalNodes();
  // A fixed number of shares, each summing fixed runs of every image's observations in
  // their order, then added up in share order: the same sums, to the last bit, whatever
  // the number of threads and however TBB schedules them (thread-local shares made runs
  // differ in the last digits, and iterations, stall stops and fold-guard decisions
  // amplify that into visibly different surfaces).
  constexpr int kShares = 8;
  std::vector<Partial> partials(kShares);
  for (Partial& p : partials) {
    p.values.assign(nnz, 0.0);
    p.rhs = Eigen::VectorXd::Zero(num_unknowns_);
  }
  obs_terms_.assign(casts.size(), {});
  for (size_t k = 0; k < casts.size(); ++k) {
    const auto& observations = casts[k];
    if (observations.empty()) continue;
    // Residual and grey-value change per unit displacement of the face, summed over
    // the channels; NaN: no observation (ResidualCorrelation).
    obs_terms_[k].assign(observations.size(), {std::numeric_limits<float>::quiet_NaN(), 0.0f});
    auto& terms = obs_terms_[k];
    const PixelRays rays(*images_[k].camera, images_[k].cam_from_world);
    const ImagePlanes& pixels = *images_[k].pixels;
    const size_t run = (observations.size() + kShares - 1) / kShares;
    tbb::parallel_for(0, kShares, [&](int share) {
      Partial& p = partials[share];
      PixelRay ray;
      ray.origin = rays.origin();
      FacetState facet;
      const size_t first = std::min(observations.size(), share * run);
      const size_t last = std::min(observations.size(), first + run);
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
        std::array<int, 6> local;
        for (int i = 0; i < 3; ++i) local[i] = i;
        for (int i = 0; i < 3; ++i) local[3 + i] = 3 + local_nodes[local_k][i];
        for (int c = 0; c < channels_; ++c) {
          for (int j = 0; j < 3; ++j) facet.grey[j] = grey_[tri[j] * channels_ + c];
          const auto& rad = radiometry_[k][c];
          const ObservationCoefficients lin =
              Linearise(ray, facet, obs.u, obs.v, Radiometry{rad[0], rad[1]});
          if (!lin.valid) continue;
          const double g = pixels.at(c, obs.x, obs.y);
          const double l = g - lin.predicted;
          // Robust weight (AdjustmentOptions::robust_k, reject_k): w scales the
          // observation's row, so the normal equations get w a a' and w a l.
          double w = 1.0;
          if (robust_scale_ > 0.0) {
            const double ratio = std::abs(l) / robust_scale_;
            if (options_.reject_k > 0.0 && ratio > options_.reject_k) {
              ++p.rejected;
              continue;
            }
            if (options_.robust_k > 0.0 && ratio > options_.robust_k) {
              w = options_.robust_k / ratio;
              ++p.downweighted;
            }
          }
          const double a[6] = {lin.dn[0], lin.dn[1], lin.dn[2], lin.grey[0], lin.grey[1], lin.grey[2]};
          auto& term = terms[o];
          term[0] = (std::isnan(term[0]) ? 0.0f : term[0]) + static_cast<float>(l);
          term[1] += static_cast<float>(a[0] + a[1] + a[2]);
          const int64_t* table = &slots_[(static_cast<size_t>(f) * channels_ + c) * kLocal * kLocal];
          int unknown[6];
          for (int i = 0; i < 3; ++i) unknown[i] = vertex_unknown_[face_vertices_[f][i]];
          for (int i = 0; i < 3; ++i) unknown[3 + i] = grey_offset_ + tri[i] * channels_ + c;
          for (int i = 0; i < 6; ++i) {
            if (unknown[i] < 0) continue;
            p.rhs[unknown[i]] += w * a[i] * l;
            const int64_t* row = table + local[i] * kLocal;
            for (int j = 0; j < 6; ++j) {
              const int64_t slot = row[local[j]];
              if (slot >= 0) p.values[slot] += w * a[i] * a[j];
            }
          }
          const std::array<int, 2>& rad_unknown = rad_unknown_[k][c];
          const double a_rad[2] = {lin.h0, lin.h1};
          for (int r = 0; r < 2; ++r) {
            const int ur = rad_unknown[r];
            if (ur < 0) continue;
            p.rhs[ur] += w * a_rad[r] * l;
            const int64_t rad_col = ur - rad_offset_;
            for (int i = 0; i < 6; ++i) {
              if (unknown[i] < 0) continue;
              const double product = w * a[i] * a_rad[r];
              p.values[row_ptr[unknown[i] + 1] - num_rad_ + rad_col] += product;
              p.values[row_ptr[ur] + unknown[i]] += product;
            }
            for (int s = 0; s < 2; ++s) {
              if (rad_unknown[s] >= 0) p.values[row_ptr[ur] + rad_unknown[s]] += w * a_rad[r] * a_rad[s];
            }
          }
          p.lpl += w * l * l;
          ++p.count;
        }
      }
    });
  }
  // Reduce the thread-local shares.
  std::vector<double>& values = normal_.values();
  std::fill(values.begin(), values.end(), 0.0);
  *rhs = Eigen::VectorXd::Zero(num_unknowns_);
  double lpl = 0.0;
  *count = 0;
  rejected_ = 0;
  downweighted_ = 0;
  for (const Partial& p : partials) {
    rejected_ += p.rejected;
    downweighted_ += p.downweighted;
    tbb::parallel_for(tbb::blocked_range<int64_t>(0, nnz, 1 << 16),
                      [&](const tbb::blocked_range<int64_t>& range) {
      for (int64_t i = range.begin(); i != range.end(); ++i) values[i] += p.values[i];
    });
    *rhs += p.rhs;
    lpl += p.lpl;
    *count += p.count;
  }
  return lpl;
}

std::vector<double> WindowAdjustment::CurrentCurvatures() const {
  std::vector<double> curvature(mesh_->n_vertices(), 0.0);
  for (size_t v = 0; v < vertex_ring_.size(); ++v) {
    const auto& ring = vertex_ring_[v];
    if (ring.empty()) continue;
    const Eigen::Vector3d x = ToEigen(mesh_->point(mesh_->vertex_handle(static_cast<int>(v))));
    const Eigen::Vector3d n = ToEigen(mesh_->normal(mesh_->vertex_handle(static_cast<int>(v))));
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    double h = 0.0;
    for (int j : ring) {
      const Eigen::Vector3d xj = ToEigen(mesh_->point(mesh_->vertex_handle(j)));
      mean += xj;
      h += (xj - x).norm();
    }
    mean /= ring.size();
    h /= ring.size();
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
  // One pseudo-observation "n . (mean of the ring - x) / h = target" for vertex v.
  auto add = [&](size_t v, const Eigen::Vector3d& n, const std::vector<int>& ring, double target) {
    const Eigen::Vector3d x = ToEigen(mesh_->point(mesh_->vertex_handle(static_cast<int>(v))));
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    double h = 0.0;
    for (int j : ring) {
      const Eigen::Vector3d xj = ToEigen(mesh_->point(mesh_->vertex_handle(j)));
      mean += xj;
      h += (xj - x).norm();
    }
    mean /= ring.size();
    h /= ring.size();
    std::vector<std::pair<int, double>> terms;
    if (vertex_unknown_[v] >= 0) terms.emplace_back(vertex_unknown_[v], -n.dot(Direction(static_cast<int>(v))) / h);
    for (int j : ring) {
      if (vertex_unknown_[j] < 0) continue;
      terms.emplace_back(vertex_unknown_[j], n.dot(Direction(j)) / (ring.size() * h));
    }
    if (terms.empty()) return;
    const double l = target - n.dot(mean - x) / h;
    for (const auto& [ui, ai] : terms) {
      (*rhs)[ui] += weight * ai * l;
      for (const auto& [uj, aj] : terms) normal_.Add(ui, uj, weight * ai * aj);
    }
    lpl += weight * l * l;
    ++*count;
  };
  for (size_t v = 0; v < vertex_ring_.size(); ++v) {
    const auto& ring = vertex_ring_[v];
    if (ring.empty()) continue;
    // Creases are meant to bend, where images say so: a crease vertex fewer than
    // min_views images see (a wall's foot behind a building, an eave seen once) has no
    // data to determine it and keeps its curvature pseudo-observation, else it is
    // held by nothing but the ridge and its sigma says it is arbitrary (issue 7).
    if (crease_vertex_[v] && vertex_views_[v] >= options_.min_views) continue;
    const double target =
        options_.regularisation == Regularisation::kAdaptive ? curvature_target_[v] : 0.0;
    add(v, ToEigen(mesh_->normal(mesh_->vertex_handle(static_cast<int>(v)))), ring, target);
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

void WindowAdjustment::SetOccluders(std::vector<Eigen::Vector3d> points,
                                    std::vector<Eigen::Vector3i> triangles) {
  occluder_points_ = std::move(points);
  occluder_triangles_ = std::move(triangles);
}

Eigen::Vector3d WindowAdjustment::Direction(int v) const {
  if (options_.displacement == Displacement::kVertical) return Eigen::Vector3d::UnitZ();
  return ToEigen(mesh_->normal(mesh_->vertex_handle(v)));
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

std::vector<int> WindowAdjustment::VertexViews(const std::vector<std::vector<PixelObservation>>& casts) const {
  // An image counts as a view of a vertex when its pixels on the faces around the vertex
  // are at least min_view_share of the best image's: a wall 3-7 degrees off a nadir
  // image's rays shows 1-2 pixels of its height there, which pins nothing down.
  const size_t num_images = images_.size();
  std::vector<int> face_pixels(face_vertices_.size() * num_images, 0);
  for (size_t k = 0; k < casts.size(); ++k) {
    for (const PixelObservation& obs : casts[k]) ++face_pixels[static_cast<size_t>(obs.face) * num_images + k];
  }
  std::vector<int> views(mesh_->n_vertices(), 0);
  std::vector<int> pixels(num_images);
  for (auto vh : mesh_->vertices()) {
    std::fill(pixels.begin(), pixels.end(), 0);
    for (auto fh : mesh_->vf_range(vh)) {
      for (size_t k = 0; k < num_images; ++k) pixels[k] += face_pixels[static_cast<size_t>(fh.idx()) * num_images + k];
    }
    const int best = *std::max_element(pixels.begin(), pixels.end());
    for (size_t k = 0; k < num_images; ++k) {
      if (pixels[k] > 0 && pixels[k] >= options_.min_view_share * best) ++views[vh.idx()];
    }
  }
  return views;
}

WindowReport WindowAdjustment::Run() {
  const auto run_start = std::chrono::steady_clock::now();
  WindowReport report;
  // Creases are decided once per window run: the grey lattice (split along creases)
  // must keep its node indices while the adjustment iterates.
  crease_edges_ = DetectCreaseEdges(*mesh_, options_.crease_angle_deg, options_.rounded_ridges);
  {
    const CornerNormals corners = ComputeCornerNormals(*mesh_, crease_edges_);
    tess_ = Tessellate(*mesh_, BuildPatches(*mesh_, corners), corners);
    report.crease_edges = corners.num_crease_edges;
    crease_vertex_.assign(mesh_->n_vertices(), false);
    for (auto vh : mesh_->vertices()) crease_vertex_[vh.idx()] = corners.vertex_sectors[vh.idx()] > 1;
  }
  scene_ = std::make_unique<SurfaceScene>(tess_);
  if (!occluder_triangles_.empty()) scene_->SetOccluders(tess_, occluder_points_, occluder_triangles_);
  BuildTopologyTables();
  BuildPattern();
  if (options_.solver == WindowSolver::kLdlt) ldlt_.Analyze(normal_);

  const int num_vertices = static_cast<int>(mesh_->n_vertices());
  std::vector<std::vector<PixelObservation>> casts;
  Eigen::VectorXd rhs, solution;
  const double bounds[3] = {options_.break_off, 2 * options_.break_off, 4 * options_.break_off};

  for (int iteration = 1; iteration <= options_.max_iterations; ++iteration) {
    IterationReport it;
    it.iteration = iteration;
    auto start = std::chrono::steady_clock::now();
    it.observations = CastAll(&casts, &it);
    it.background = DropBackground(&casts);
    it.observations -= it.background;
    it.seconds_cast = Seconds(start);
    if (it.observations == 0) {
      throw std::runtime_error("WindowAdjustment: no image sees the window (0 observations)");
    }
    if (grey_.empty() || (iteration == 1 && !grey_given_)) InitialiseGrey(casts);
    vertex_views_ = VertexViews(casts);
    robust_scale_ = options_.robust_k > 0.0 || options_.reject_k > 0.0 ? RobustScale(casts) : 0.0;
    it.robust_scale = robust_scale_;

    start = std::chrono::steady_clock::now();
    long long count = 0, pseudo = 0;
    double lpl = Accumulate(casts, &rhs, &count);
    lpl += AccumulateCurvature(&rhs, &pseudo);
    long long silhouette_outside = 0;
    lpl += AccumulateSilhouette(&rhs, &it.silhouette, &silhouette_outside);
    it.silhouette_outside = silhouette_outside;
    pseudo += it.silhouette;
    const int determined = AddRidge();
    it.seconds_linearise = Seconds(start);

    start = std::chrono::steady_clock::now();
    solution = Eigen::VectorXd::Zero(num_unknowns_);
    if (options_.solver == WindowSolver::kLdlt && ldlt_.Factorize(normal_)) {
      solution = ldlt_.Solve(rhs);
    } else {
      // PCG, also when LDL^T met a non-positive pivot (N numerically indefinite).
      const PcgSummary pcg = SolvePcg(normal_, rhs, options_.pcg, &solution);
      it.cg_iterations = pcg.iterations;
    }
    rhs_ = rhs;
    it.seconds_solve = Seconds(start);

    const long long redundancy = count + pseudo - determined;
    const double vpv = std::max(lpl - solution.dot(rhs), 0.0);
    it.sigma0 = redundancy > 0 ? std::sqrt(vpv / redundancy) : 0.0;
    it.rejected = rejected_;
    it.downweighted = downweighted_;
    report.observations = count;
    report.pseudo_observations = pseudo;
    report.background = it.background;
    report.rejected = rejected_;
    report.downweighted = downweighted_;
    report.silhouette = it.silhouette;
    report.silhouette_outside = it.silhouette_outside;
    report.unknowns = determined;
    report.redundancy = redundancy;

    // Update: vertices along their (current) normals, then grey values, radiometry.
    start = std::chrono::steady_clock::now();
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
    if (options_.fold_guard) it.fold_limited = LimitFoldingSteps(mesh_, before);
    UpdateVertexNormals(mesh_);
    if (options_.regularisation == Regularisation::kAdaptive) curvature_target_ = CurrentCurvatures();
    UpdateTessellationPoints(BuildPatches(*mesh_, ComputeCornerNormals(*mesh_, crease_edges_)), &tess_);
    scene_->Update(tess_);
    it.seconds_update = Seconds(start);
    it.max_dn_interior = max_dn[0];
    it.max_dn_border = max_dn[1];
    it.max_dn_corner = max_dn[2];
    report.cg_iterations_total += it.cg_iterations;
    report.iterations.push_back(it);
    report.sigma0 = it.sigma0;
    if (scale == 1.0 && max_dn[0] < bounds[0] && max_dn[1] < bounds[1] && max_dn[2] < bounds[2]) {
      report.converged = true;
      break;
    }
    if (Stalled(report.iterations)) {
      report.stalled = true;
      break;
    }
  }

  report.vertex_views = VertexViews(casts);

  const CorrelatedResiduals correlated = ResidualCorrelation(casts);
  report.residual_rho_x = correlated.rho_x;
  report.residual_rho_y = correlated.rho_y;
  report.variance_factor = options_.correlated_residuals ? correlated.variance_factor : 1.0;
  report.vertex_sigma.assign(num_vertices, 0.0);
  report.vertex_flags.assign(num_vertices, kVertexOk);
  if (options_.compute_precision && num_geometry_ > 0 &&
      num_unknowns_ <= options_.max_precision_unknowns) {
    report.precision_computed = true;
    const auto start = std::chrono::steady_clock::now();
    std::vector<int> geometry(num_geometry_);
    for (int i = 0; i < num_geometry_; ++i) geometry[i] = i;
    // The last iteration's N: with LDL^T its factor is at hand.
    const Eigen::VectorXd q =
        ldlt_.factorized() ? ldlt_.InverseDiagonal(geometry) : InverseDiagonal(normal_, geometry);
    for (int v = 0; v < num_vertices; ++v) {
      if (vertex_unknown_[v] >= 0) report.vertex_sigma[v] = report.sigma0 * std::sqrt(report.variance_factor * std::max(q[vertex_unknown_[v]], 0.0));
    }
    // A vertex fewer than min_views images see is held by the curvature pseudo-
    // observations (also on a crease); its formal sigma would report the smoothness
    // prior as if it had been measured. Its sigma is taken from the data alone, N without
    // the pseudo-observations, when that is larger (issue 7).
    std::vector<int> few_view, few_unknowns;
    for (int v = 0; v < num_vertices; ++v) {
      if (vertex_unknown_[v] >= 0 && report.vertex_views[v] < options_.min_views) {
        few_view.push_back(v);
        few_unknowns.push_back(vertex_unknown_[v]);
      }
    }
    if (!few_view.empty()) {
      Eigen::VectorXd data_rhs;
      long long data_count = 0;
      Accumulate(casts, &data_rhs, &data_count);
      AddRidge();
      Eigen::VectorXd q_data;
      if (options_.solver == WindowSolver::kLdlt && ldlt_.Factorize(normal_)) {
        q_data = ldlt_.InverseDiagonal(few_unknowns);
      } else {
        try {
          q_data = InverseDiagonal(normal_, few_unknowns);
        } catch (const std::runtime_error&) {
          // N of the data alone numerically singular: the formal sigma stands.
        }
      }
      for (size_t i = 0; i < static_cast<size_t>(q_data.size()); ++i) {
        const double q_v = std::max(q[few_unknowns[i]], q_data[i]);
        report.vertex_sigma[few_view[i]] = report.sigma0 * std::sqrt(report.variance_factor * std::max(q_v, 0.0));
      }
    }
    report.seconds_precision = Seconds(start);
  }
  for (int v = 0; v < num_vertices; ++v) {
    uint8_t flags = kVertexOk;
    if (fixed_[v]) flags |= kVertexFixed;
    if (report.vertex_views[v] < options_.min_views) flags |= kVertexFewViews;
    if (options_.max_sigma > 0.0 && report.vertex_sigma[v] > options_.max_sigma) flags |= kVertexHighSigma;
    report.vertex_flags[v] = flags;
  }
  report.radiometry = radiometry_;
  report.seconds_total = Seconds(run_start);
  return report;
}

}  // namespace facets
