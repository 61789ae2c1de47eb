// WindowAdjustment: the precision at the end of a run (DESIGN.md section 6). The standard
// deviation of each vertex's normal displacement is sigma0 sqrt(q_vv) with q_vv the
// diagonal of N^-1, scaled by the variance factor of correlated residuals; a vertex
// fewer than min_views images see takes its sigma from the data alone.
#include "engine/solver/window_adjustment.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <unordered_map>

#include "engine/solver/window_adjustment_internal.h"

namespace facets {

using window_internal::Seconds;

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

void WindowAdjustment::FinishReport(const std::vector<std::vector<PixelObservation>>& casts,
                                    WindowReport* report) {
  const int num_vertices = static_cast<int>(mesh_->n_vertices());
  report->vertex_views = VertexViews(casts);

  const CorrelatedResiduals correlated =
      options_.residual_correlation ? ResidualCorrelation(casts) : CorrelatedResiduals{};
  report->residual_rho_x = correlated.rho_x;
  report->residual_rho_y = correlated.rho_y;
  report->variance_factor = options_.correlated_residuals ? correlated.variance_factor : 1.0;
  report->vertex_sigma.assign(num_vertices, 0.0);
  report->vertex_flags.assign(num_vertices, kVertexOk);
  if (options_.compute_precision && num_geometry_ > 0 &&
      num_unknowns_ <= options_.max_precision_unknowns) {
    ComputePrecision(casts, report);
  }
  for (int v = 0; v < num_vertices; ++v) {
    uint8_t flags = kVertexOk;
    if (fixed_[v]) flags |= kVertexFixed;
    if (report->vertex_views[v] < options_.min_views) flags |= kVertexFewViews;
    if (options_.max_sigma > 0.0 && report->vertex_sigma[v] > options_.max_sigma) flags |= kVertexHighSigma;
    report->vertex_flags[v] = flags;
  }
  report->radiometry = radiometry_;
}

void WindowAdjustment::ComputePrecision(const std::vector<std::vector<PixelObservation>>& casts,
                                        WindowReport* report) {
  const int num_vertices = static_cast<int>(mesh_->n_vertices());
  report->precision_computed = true;
  const auto start = std::chrono::steady_clock::now();
  std::vector<int> geometry(num_geometry_);
  for (int i = 0; i < num_geometry_; ++i) geometry[i] = i;
  // The last iteration's N: with LDL^T its factor is at hand.
  const Eigen::VectorXd q =
      ldlt_.factorized() ? ldlt_.InverseDiagonal(geometry) : InverseDiagonal(normal_, geometry);
  for (int v = 0; v < num_vertices; ++v) {
    if (vertex_unknown_[v] >= 0) report->vertex_sigma[v] = report->sigma0 * std::sqrt(report->variance_factor * std::max(q[vertex_unknown_[v]], 0.0));
  }
  // A vertex fewer than min_views images see is held by the curvature pseudo-
  // observations (also on a crease); its formal sigma would report the smoothness
  // prior as if it had been measured. Its sigma is taken from the data alone, N without
  // the pseudo-observations, when that is larger.
  std::vector<int> few_view, few_unknowns;
  for (int v = 0; v < num_vertices; ++v) {
    if (vertex_unknown_[v] >= 0 && report->vertex_views[v] < options_.min_views) {
      few_view.push_back(v);
      few_unknowns.push_back(vertex_unknown_[v]);
    }
  }
  if (!few_view.empty()) SigmaFromDataAlone(casts, few_view, few_unknowns, q, report);
  report->seconds_precision = Seconds(start);
}

void WindowAdjustment::SigmaFromDataAlone(const std::vector<std::vector<PixelObservation>>& casts,
                                          const std::vector<int>& few_view, const std::vector<int>& few_unknowns,
                                          const Eigen::VectorXd& q, WindowReport* report) {
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
    report->vertex_sigma[few_view[i]] = report->sigma0 * std::sqrt(report->variance_factor * std::max(q_v, 0.0));
  }
}

}  // namespace facets
