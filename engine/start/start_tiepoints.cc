#include "engine/start/start_tiepoints.h"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <random>
#include <cmath>
#include <functional>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <unordered_map>

namespace facets {
namespace {

double Median(std::vector<double> v) {
  const size_t mid = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + mid, v.end());
  if (v.size() % 2 == 1) return v[mid];
  const double upper = v[mid];
  return 0.5 * (upper + *std::max_element(v.begin(), v.begin() + mid));
}

// Robust scale of values around their median: 1.4826 x MAD (the standard deviation
// for normally distributed values).
double RobustSigma(const std::vector<double>& values, double median) {
  std::vector<double> dev;
  dev.reserve(values.size());
  for (double v : values) dev.push_back(std::abs(v - median));
  return 1.4826 * Median(dev);
}

// z = a + b x + c y by least squares over the points flagged in `use`.
Eigen::Vector3d FitPlaneZ(const std::vector<Eigen::Vector3d>& points, const std::vector<bool>& use) {
  Eigen::Matrix3d n = Eigen::Matrix3d::Zero();
  Eigen::Vector3d b = Eigen::Vector3d::Zero();
  for (size_t i = 0; i < points.size(); ++i) {
    if (!use[i]) continue;
    const Eigen::Vector3d row(1.0, points[i].x(), points[i].y());
    n += row * row.transpose();
    b += row * points[i].z();
  }
  return n.ldlt().solve(b);
}

// Plane fitted, then refitted without the points beyond the MAD bound of its
// residuals, a few times (the first fit is pulled by the outliers, the next ones not).
Eigen::Vector3d RobustPlane(const std::vector<Eigen::Vector3d>& points,
                            const TiePointStartOptions& options, int* rejected) {
  std::vector<bool> use(points.size(), true);
  // Start from the median height: a least-squares first fit could be tilted by blunders.
  std::vector<double> z;
  for (const auto& p : points) z.push_back(p.z());
  Eigen::Vector3d plane(Median(z), 0.0, 0.0);
  for (int round = 0; round < 5; ++round) {
    std::vector<double> residuals;
    for (const auto& p : points) residuals.push_back(p.z() - plane.dot(Eigen::Vector3d(1, p.x(), p.y())));
    const double centre = Median(residuals);
    const double bound = std::max(options.mad_factor * RobustSigma(residuals, centre), options.min_tolerance);
    int kept = 0;
    for (size_t i = 0; i < points.size(); ++i) {
      use[i] = std::abs(residuals[i] - centre) <= bound;
      kept += use[i] ? 1 : 0;
    }
    if (kept < 3) break;
    plane = FitPlaneZ(points, use);
  }
  *rejected = static_cast<int>(std::count(use.begin(), use.end(), false));
  return plane;
}

// Points bucketed in square cells for the neighbourhood queries.
class PointBuckets {
 public:
  PointBuckets(const std::vector<Eigen::Vector3d>& points, const Eigen::Vector2d& min, double cell)
      : points_(points), min_(min), cell_(cell) {
    for (size_t i = 0; i < points.size(); ++i) {
      cells_[Key(Cell(points[i].x() - min.x()), Cell(points[i].y() - min.y()))].push_back(static_cast<int>(i));
    }
  }
  // The points within `radius` of (x, y).
  std::vector<Eigen::Vector3d> PointsNear(double x, double y, double radius) const {
    std::vector<Eigen::Vector3d> z;
    const long i0 = Cell(x - radius - min_.x()), i1 = Cell(x + radius - min_.x());
    const long j0 = Cell(y - radius - min_.y()), j1 = Cell(y + radius - min_.y());
    for (long j = j0; j <= j1; ++j) {
      for (long i = i0; i <= i1; ++i) {
        const auto it = cells_.find(Key(i, j));
        if (it == cells_.end()) continue;
        for (int k : it->second) {
          const Eigen::Vector3d& p = points_[k];
          if (std::hypot(p.x() - x, p.y() - y) <= radius) z.push_back(p);
        }
      }
    }
    return z;
  }

 private:
  long Cell(double offset) const { return static_cast<long>(std::floor(offset / cell_)); }
  static long long Key(long i, long j) { return (static_cast<long long>(i) << 32) ^ (j & 0xffffffffLL); }
  const std::vector<Eigen::Vector3d>& points_;
  Eigen::Vector2d min_;
  double cell_;
  std::unordered_map<long long, std::vector<int>> cells_;
};

// Triples of n points to fit planes through: all of them for small neighbourhoods, else
// a fixed pseudo-random set (deterministic: the same points give the same start).
std::vector<std::array<int, 3>> ConsensusTriples(int n) {
  std::vector<std::array<int, 3>> triples;
  if (n <= 14) {
    for (int i = 0; i < n; ++i)
      for (int j = i + 1; j < n; ++j)
        for (int k = j + 1; k < n; ++k) triples.push_back({i, j, k});
  } else {
    std::mt19937 rng(12345u + static_cast<unsigned>(n));
    std::uniform_int_distribution<int> pick(0, n - 1);
    while (triples.size() < 400) {
      const int i = pick(rng), j = pick(rng), k = pick(rng);
      if (i != j && j != k && i != k) triples.push_back({i, j, k});
    }
  }
  return triples;
}

// Flags the points within the consensus tolerance of a plane z = a + b x + c y; returns
// how many.
using InliersOf = std::function<int(const Eigen::Vector3d& plane, std::vector<bool>* use)>;

// Of the planes through the triples (points relative to the node), the one with at least
// min_inliers agreeing points whose agreeing points weigh most (weights
// exp(-d^2 / weight_radius^2)); returns its inlier count (0: none), *plane and *use.
int BestConsensusPlane(const std::vector<Eigen::Vector3d>& local, const InliersOf& inliers_of, int min_inliers,
                       double weight_radius, Eigen::Vector3d* best_plane, std::vector<bool>* best_use) {
  const int n = static_cast<int>(local.size());
  std::vector<bool> use(n);
  // Score: inliers weighted by closeness to the node, so a small roof under the node
  // outweighs more ground points further out.
  std::vector<double> weight(n);
  const double r0 = weight_radius;
  for (int i = 0; i < n; ++i) weight[i] = std::exp(-local[i].head<2>().squaredNorm() / (r0 * r0));
  double best_score = 0.0;
  int best = 0;
  for (const auto& t : ConsensusTriples(n)) {
    Eigen::Matrix3d a;
    Eigen::Vector3d b;
    for (int r = 0; r < 3; ++r) {
      a.row(r) << 1.0, local[t[r]].x(), local[t[r]].y();
      b[r] = local[t[r]].z();
    }
    // Nearly collinear triples give arbitrary tilts: skip them.
    const double area = std::abs((local[t[1]] - local[t[0]]).head<2>().homogeneous().cross(
                                     (local[t[2]] - local[t[0]]).head<2>().homogeneous())[2]);
    const double span = std::max({(local[t[1]] - local[t[0]]).head<2>().squaredNorm(),
                                  (local[t[2]] - local[t[0]]).head<2>().squaredNorm(),
                                  (local[t[2]] - local[t[1]]).head<2>().squaredNorm()});
    if (area < 0.05 * span) continue;
    const Eigen::Vector3d plane = a.lu().solve(b);
    // Steeper than 45 degrees: a wall between ground and roof points, not a surface.
    if (plane.tail<2>().norm() > 1.0) continue;
    const int kept = inliers_of(plane, &use);
    if (kept < min_inliers) continue;
    double score = 0.0;
    for (int i = 0; i < n; ++i) score += use[i] ? weight[i] : 0.0;
    if (score > best_score) {
      best_score = score;
      best = kept;
      *best_plane = plane;
      *best_use = use;
    }
  }
  return best;
}

// Height at (x, y) of the local plane with the best consensus: planes through
// triples of the neighbourhood's points, each scored by the points within
// consensus_tolerance; the best one refitted by least squares to its inliers (twice).
// Consensus and not median/MAD: where blunders happen to make up half of a small
// neighbourhood they still scatter over metres while the good points agree within
// centimetres, so the agreeing set wins (the median lands in between). A plane and not
// a level, so a slope does not bias the node towards the side with more points (or the
// one-sided neighbourhood at the border). Among planes with at least min_inliers
// agreeing points the one whose agreeing points lie nearest the node (weights
// exp(-d^2 / weight_radius^2)) wins: the roof under the node, not the larger ground
// around it. Empty when no plane has min_inliers agreeing points.
// `offset` receives the distance from (x, y) to the inliers' centroid.
std::optional<double> LocalRobustHeight(const std::vector<Eigen::Vector3d>& near, double x, double y,
                                        const TiePointStartOptions& options, double weight_radius,
                                        double* offset) {
  const int n = static_cast<int>(near.size());
  if (n < std::max(3, options.min_points)) return std::nullopt;
  std::vector<Eigen::Vector3d> local;
  for (const auto& p : near) local.emplace_back(p.x() - x, p.y() - y, p.z());
  const double tolerance = options.consensus_tolerance;
  const InliersOf inliers_of = [&](const Eigen::Vector3d& plane, std::vector<bool>* use) {
    int kept = 0;
    for (int i = 0; i < n; ++i) {
      (*use)[i] = std::abs(local[i].z() - plane.dot(Eigen::Vector3d(1, local[i].x(), local[i].y()))) <= tolerance;
      kept += (*use)[i] ? 1 : 0;
    }
    return kept;
  };
  std::vector<bool> best_use(n);
  Eigen::Vector3d best_plane = Eigen::Vector3d::Zero();
  const int best = BestConsensusPlane(local, inliers_of, options.min_inliers, weight_radius, &best_plane, &best_use);
  if (best < options.min_inliers) return std::nullopt;
  for (int round = 0; round < 2; ++round) {
    const Eigen::Vector3d refit = FitPlaneZ(local, best_use);
    if (!refit.allFinite() || refit.tail<2>().norm() > 1.0) break;
    best_plane = refit;
    if (inliers_of(best_plane, &best_use) < options.min_inliers) return std::nullopt;
  }
  Eigen::Vector2d centroid = Eigen::Vector2d::Zero();
  int kept = 0;
  for (int i = 0; i < n; ++i) {
    if (!best_use[i]) continue;
    centroid += local[i].head<2>();
    ++kept;
  }
  *offset = (centroid / kept).norm();
  return best_plane[0];
}

// The height at node (x, y) from the tie points around it: the consensus plane of the
// smallest neighbourhood (radius_nodes node steps, doubled up to max_radius_nodes) that
// has one with its agreeing points around the node; empty when none has.
std::optional<double> NodeHeightFromPoints(const PointBuckets& buckets, double x, double y, double step,
                                           double weight_radius, const TiePointStartOptions& options) {
  for (double radius = options.radius_nodes * step; radius <= options.max_radius_nodes * step * 1.0001;
       radius *= 2) {
    std::vector<Eigen::Vector3d> near = buckets.PointsNear(x, y, radius);
    // Dense tie points (a full COLMAP model): the nearest kMaxNeighbours suffice and
    // keep the consensus search bounded per node.
    constexpr size_t kMaxNeighbours = 64;
    if (near.size() > kMaxNeighbours) {
      auto closer = [x, y](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
        return std::hypot(a.x() - x, a.y() - y) < std::hypot(b.x() - x, b.y() - y);
      };
      std::nth_element(near.begin(), near.begin() + kMaxNeighbours, near.end(), closer);
      near.resize(kMaxNeighbours);
    }
    if (static_cast<int>(near.size()) < options.min_points) continue;
    double offset = 0.0;
    const std::optional<double> fitted = LocalRobustHeight(near, x, y, options, weight_radius, &offset);
    if (!fitted) continue;
    // All agreeing points off to one side (the edge of a hole): the plane would be
    // extrapolated; a larger neighbourhood may take the other side in, else the node
    // takes the robust plane. (At the region's border a half disc puts the centroid
    // at 0.42 radius, a quarter disc at 0.6.)
    if (offset > 0.7 * radius) continue;
    return fitted;
  }
  return std::nullopt;
}

// One smoothing pass: each node's deviation from the robust plane halfway to the mean
// deviation of its (up to 4) grid neighbours. Smoothing the deviation keeps a plane
// exact, also at the border where the neighbours are one-sided.
void SmoothDeviations(const Eigen::Vector3d& plane, TiePointHeightGrid* grid) {
  const Eigen::Vector2d range = grid->max - grid->min;
  auto plane_at = [&](int i, int j) {
    return plane.dot(Eigen::Vector3d(1, grid->min.x() + range.x() * i / grid->nx,
                                     grid->min.y() + range.y() * j / grid->ny));
  };
  std::vector<double> next = grid->heights;
  for (int j = 0; j <= grid->ny; ++j) {
    for (int i = 0; i <= grid->nx; ++i) {
      double sum = 0.0;
      int count = 0;
      auto add = [&](int a, int b) {
        if (a < 0 || b < 0 || a > grid->nx || b > grid->ny) return;
        sum += grid->heights[static_cast<size_t>(b) * (grid->nx + 1) + a] - plane_at(a, b);
        ++count;
      };
      add(i - 1, j);
      add(i + 1, j);
      add(i, j - 1);
      add(i, j + 1);
      const size_t k = static_cast<size_t>(j) * (grid->nx + 1) + i;
      const double own = grid->heights[k] - plane_at(i, j);
      next[k] = plane_at(i, j) + 0.5 * own + 0.5 * sum / count;
    }
  }
  grid->heights.swap(next);
}

}  // namespace

void TiePointStartOptions::Check() const {
  auto fail = [](const std::string& what) { throw std::invalid_argument("tie-point start: " + what); };
  if (min_points_total < 3) fail("min_points_total must be >= 3");
  if (min_points < 1) fail("min_points must be >= 1");
  if (!(radius_nodes > 0) || !(max_radius_nodes >= radius_nodes)) {
    fail("need 0 < radius_nodes <= max_radius_nodes");
  }
  if (!(mad_factor > 0)) fail("mad_factor must be > 0");
  if (!(min_tolerance >= 0)) fail("min_tolerance must be >= 0");
  if (!(consensus_tolerance > 0)) fail("consensus_tolerance must be > 0");
  if (smoothing_passes < 0) fail("smoothing_passes must be >= 0");
  if (min_inliers < 3) fail("min_inliers must be >= 3");
  if (!(weight_radius_nodes > 0)) fail("weight_radius_nodes must be > 0");
}

std::string TiePointStartReport::Brief() const {
  std::ostringstream out;
  out << points_in_region << " tie points over the region (" << points_rejected_by_plane
      << " off the robust plane z = " << plane[0] << " + " << plane[1] << " x + " << plane[2]
      << " y), " << nodes << " nodes: " << nodes_from_points << " from their points, "
      << nodes_from_plane << " from the plane";
  return out.str();
}

double TiePointHeightGrid::At(double x, double y) const {
  const int i = std::clamp(static_cast<int>(std::lround((x - min.x()) / (max.x() - min.x()) * nx)), 0, nx);
  const int j = std::clamp(static_cast<int>(std::lround((y - min.y()) / (max.y() - min.y()) * ny)), 0, ny);
  return heights[static_cast<size_t>(j) * (nx + 1) + i];
}

StartSurfaceKind StartSurfaceFromName(const std::string& name) {
  if (name == "auto") return StartSurfaceKind::kAuto;
  if (name == "plane") return StartSurfaceKind::kPlane;
  if (name == "tiepoints") return StartSurfaceKind::kTiePoints;
  throw std::invalid_argument("start surface '" + name + "': expected auto, plane or tiepoints");
}

bool UseTiePointStart(StartSurfaceKind kind, int points_in_region, bool plane_height_chosen,
                      const TiePointStartOptions& options) {
  switch (kind) {
    case StartSurfaceKind::kPlane: return false;
    case StartSurfaceKind::kTiePoints: return true;
    case StartSurfaceKind::kAuto: break;
  }
  return !plane_height_chosen && points_in_region >= options.min_points_total;
}

std::vector<Eigen::Vector3d> TiePointsInRegion(const ImageBlock& block, const RegionOfInterest& roi) {
  std::vector<Eigen::Vector3d> inside;
  for (const auto& p : block.points) {
    if (roi.Contains(p.xyz)) inside.push_back(p.xyz);
  }
  return inside;
}

bool OverFootprint(const RegionOfInterest& roi, const Eigen::Vector3d& p) {
  return p.x() >= roi.min.x() && p.x() <= roi.max.x() && p.y() >= roi.min.y() && p.y() <= roi.max.y();
}

std::vector<Eigen::Vector3d> TiePointsOverFootprint(const ImageBlock& block, const RegionOfInterest& roi) {
  std::vector<Eigen::Vector3d> over;
  for (const auto& p : block.points) {
    if (OverFootprint(roi, p.xyz)) over.push_back(p.xyz);
  }
  return over;
}

TiePointHeightGrid FitTiePointHeights(const std::vector<Eigen::Vector3d>& all_points,
                                      const RegionOfInterest& roi, double spacing,
                                      const TiePointStartOptions& options, TiePointStartReport* report) {
  options.Check();
  if (!(spacing > 0)) throw std::invalid_argument("tie-point start: spacing must be > 0");
  std::vector<Eigen::Vector3d> points;
  for (const auto& p : all_points) {
    if (OverFootprint(roi, p)) points.push_back(p);
  }
  if (static_cast<int>(points.size()) < options.min_points_total) {
    throw std::runtime_error("tie-point start: " + std::to_string(points.size()) +
                             " tie points over the region of interest, need at least " +
                             std::to_string(options.min_points_total));
  }
  TiePointStartReport local;
  TiePointStartReport& r = report ? *report : local;
  r = TiePointStartReport();
  r.points_in_region = static_cast<int>(points.size());
  r.plane = RobustPlane(points, options, &r.points_rejected_by_plane);

  // The node layout of MakeStartGrid (mesh/tin.cc): range / ceil(range / spacing).
  TiePointHeightGrid grid;
  grid.min = roi.min.head<2>();
  grid.max = roi.max.head<2>();
  const Eigen::Vector2d range = grid.max - grid.min;
  grid.nx = std::max(1, static_cast<int>(std::ceil(range.x() / spacing - 1e-9)));
  grid.ny = std::max(1, static_cast<int>(std::ceil(range.y() / spacing - 1e-9)));
  const double step = std::max(range.x() / grid.nx, range.y() / grid.ny);
  const double weight_radius = options.weight_radius_nodes * step;
  const PointBuckets buckets(points, grid.min, options.radius_nodes * step);
  grid.heights.resize(static_cast<size_t>(grid.nx + 1) * (grid.ny + 1));
  for (int j = 0; j <= grid.ny; ++j) {
    for (int i = 0; i <= grid.nx; ++i) {
      const double x = grid.min.x() + range.x() * i / grid.nx;
      const double y = grid.min.y() + range.y() * j / grid.ny;
      double& z = grid.heights[static_cast<size_t>(j) * (grid.nx + 1) + i];
      z = r.plane.dot(Eigen::Vector3d(1, x, y));
      const std::optional<double> fitted = NodeHeightFromPoints(buckets, x, y, step, weight_radius, options);
      if (fitted) {
        z = *fitted;
        ++r.nodes_from_points;
      }
    }
  }
  r.nodes = static_cast<int>(grid.heights.size());
  r.nodes_from_plane = r.nodes - r.nodes_from_points;

  for (int pass = 0; pass < options.smoothing_passes; ++pass) SmoothDeviations(r.plane, &grid);
  return grid;
}

TinMesh StartFromTiePoints(const std::vector<Eigen::Vector3d>& points, const RegionOfInterest& roi,
                           double spacing, const TiePointStartOptions& options, TiePointStartReport* report) {
  const TiePointHeightGrid grid = FitTiePointHeights(points, roi, spacing, options, report);
  StartGridOptions start;
  start.min = grid.min;
  start.max = grid.max;
  start.spacing = spacing;
  start.height = [&grid](double x, double y) { return grid.At(x, y); };
  return MakeStartGrid(start);
}

}  // namespace facets
