#include "engine/start/start_closed.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "engine/pipeline/reconstruction.h"
#include "io/ply_io.h"
#include "mesh/local_ops.h"
#include "mesh/surface_validity.h"

namespace facets {
namespace {

double Median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  auto middle = v.begin() + v.size() / 2;
  std::nth_element(v.begin(), middle, v.end());
  return *middle;
}

// Tukey's biweight for residual r at scale s: 0 beyond kTukey s. 3 s rather than the
// usual 4.685 s: a floor around the object lies only a few lobe heights off the sphere.
constexpr double kTukey = 3.0;
double TukeyWeight(double r, double s) {
  const double u = r / (kTukey * s);
  return std::abs(u) >= 1.0 ? 0.0 : (1.0 - u * u) * (1.0 - u * u);
}

// Weighted algebraic sphere: 2 p.c + d = |p|^2, R^2 = d + |c|^2 (p relative to `origin`).
bool FitSphere(const std::vector<Eigen::Vector3d>& p, const std::vector<double>& w,
               const Eigen::Vector3d& origin, Eigen::Vector3d* centre, double* radius) {
  Eigen::Matrix4d n = Eigen::Matrix4d::Zero();
  Eigen::Vector4d b = Eigen::Vector4d::Zero();
  for (size_t i = 0; i < p.size(); ++i) {
    if (w[i] <= 0.0) continue;
    const Eigen::Vector3d q = p[i] - origin;
    const Eigen::Vector4d a(2 * q.x(), 2 * q.y(), 2 * q.z(), 1.0);
    n += w[i] * a * a.transpose();
    b += w[i] * a * q.squaredNorm();
  }
  const Eigen::Vector4d x = n.ldlt().solve(b);
  const double r2 = x[3] + x.head<3>().squaredNorm();
  if (!x.allFinite() || !(r2 > 0.0)) return false;
  *centre = origin + x.head<3>();
  *radius = std::sqrt(r2);
  return true;
}

// Radial distance of p to the ellipsoid (along the ray from its centre).
double RadialDistance(const Ellipsoid& e, const Eigen::Vector3d& p) {
  const Eigen::Vector3d d = p - e.centre;
  const double scaled = (e.axes.transpose() * d).cwiseQuotient(e.radii).norm();
  if (scaled <= 0.0) return -e.MeanRadius();
  return d.norm() * (1.0 - 1.0 / scaled);
}

// Weighted algebraic quadric x'Ax + b'x = 1 (x relative to `origin`) as an ellipsoid.
bool FitEllipsoid(const std::vector<Eigen::Vector3d>& p, const std::vector<double>& w,
                  const Eigen::Vector3d& origin, Ellipsoid* out) {
  using Vector9d = Eigen::Matrix<double, 9, 1>;
  Eigen::Matrix<double, 9, 9> n = Eigen::Matrix<double, 9, 9>::Zero();
  Vector9d b = Vector9d::Zero();
  int used = 0;
  for (size_t i = 0; i < p.size(); ++i) {
    if (w[i] <= 0.0) continue;
    const Eigen::Vector3d q = p[i] - origin;
    Vector9d a;
    a << q.x() * q.x(), q.y() * q.y(), q.z() * q.z(), 2 * q.x() * q.y(), 2 * q.x() * q.z(),
        2 * q.y() * q.z(), 2 * q.x(), 2 * q.y(), 2 * q.z();
    n += w[i] * a * a.transpose();
    b += w[i] * a;
    ++used;
  }
  if (used < 12) return false;
  const Vector9d x = n.ldlt().solve(b);
  if (!x.allFinite()) return false;
  Eigen::Matrix3d a;
  a << x[0], x[3], x[4], x[3], x[1], x[5], x[4], x[5], x[2];
  const Eigen::Vector3d lin(x[6], x[7], x[8]);
  // x'Ax + 2 lin'x = 1  <=>  (x - c)'A(x - c) = 1 + c'Ac with c = -A^-1 lin.
  const Eigen::Vector3d c = -a.ldlt().solve(lin);
  const double k = 1.0 + c.dot(a * c);
  if (!c.allFinite() || !(k > 0.0)) return false;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(a / k);
  if (!(eig.eigenvalues().array() > 0.0).all()) return false;
  out->centre = origin + c;
  out->axes = eig.eigenvectors();
  if (out->axes.determinant() < 0.0) out->axes.col(2) *= -1.0;
  out->radii = eig.eigenvalues().cwiseSqrt().cwiseInverse();
  return true;
}

// The start ellipsoid (or sphere) while it is fitted to the tie points.
struct StartShape {
  const std::vector<Eigen::Vector3d>& points;
  double size;  // the first radius: median distance of the points to the centre guess
  Ellipsoid e;
  bool is_sphere;

  bool Plausible(const Ellipsoid& x) const {
    return x.radii.maxCoeff() < 4.0 * x.radii.minCoeff() && x.radii.minCoeff() > 0.1 * size &&
           x.radii.maxCoeff() < 5.0 * size;
  }
  // The ellipsoid fitted with weights w when it is plausible, else the sphere (the
  // shape stays when both fail).
  void Refit(const std::vector<double>& w) {
    Ellipsoid next;
    if (FitEllipsoid(points, w, e.centre, &next) && Plausible(next)) {
      e = next;
      is_sphere = false;
      return;
    }
    Eigen::Vector3d c;
    double r = 0.0;
    if (FitSphere(points, w, e.centre, &c, &r)) {
      e.centre = c;
      e.axes.setIdentity();
      e.radii = Eigen::Vector3d::Constant(r);
      is_sphere = true;
    }
  }
};

// Fits to the half of the points closest to the current surface (concentration steps
// of least trimmed squares): up to half of the points may be floor or background;
// re-weighting all points instead lets the fit drift onto the floor.
void ConcentrateOnClosestHalf(StartShape* shape) {
  const std::vector<Eigen::Vector3d>& points = shape->points;
  const size_t n = points.size();
  const size_t half = (n + 1) / 2;
  std::vector<double> r(n), w(n);
  std::vector<size_t> order(n), previous;
  for (int iteration = 0; iteration < 50; ++iteration) {
    for (size_t i = 0; i < n; ++i) r[i] = std::abs(RadialDistance(shape->e, points[i]));
    for (size_t i = 0; i < n; ++i) order[i] = i;
    std::nth_element(order.begin(), order.begin() + half, order.end(),
                     [&](size_t a, size_t b) { return r[a] < r[b]; });
    std::vector<size_t> subset(order.begin(), order.begin() + half);
    std::sort(subset.begin(), subset.end());
    if (subset == previous) break;
    previous = subset;
    std::fill(w.begin(), w.end(), 0.0);
    for (size_t i : subset) w[i] = 1.0;
    shape->Refit(w);
  }
}

// Scale from the closest quarter of all points (a quantile of the inliers' residuals
// as long as at least half are inliers: over-estimates sigma at most 2x), then Tukey
// weights and a re-fit, the scale re-estimated from the inliers only. Returns the scale
// (m); *r: the points' radial distances to the final shape.
double TukeyRefit(StartShape* shape, std::vector<double>* r) {
  const std::vector<Eigen::Vector3d>& points = shape->points;
  const size_t n = points.size();
  for (size_t i = 0; i < n; ++i) (*r)[i] = std::abs(RadialDistance(shape->e, points[i]));
  std::vector<double> sorted = *r;
  std::nth_element(sorted.begin(), sorted.begin() + n / 4, sorted.end());
  double s = std::max(sorted[n / 4] / 0.3186, 1e-4 * shape->size);
  std::vector<double> w(n);
  for (int iteration = 0; iteration < 5; ++iteration) {
    for (size_t i = 0; i < n; ++i) w[i] = TukeyWeight((*r)[i], s);
    shape->Refit(w);
    std::vector<double> inlier;
    for (size_t i = 0; i < n; ++i) {
      (*r)[i] = std::abs(RadialDistance(shape->e, points[i]));
      if (w[i] > 0.0) inlier.push_back((*r)[i]);
    }
    s = std::max(1.4826 * Median(inlier), 1e-4 * shape->size);
  }
  return s;
}

TinMesh Scaled(const TinMesh& start, const Eigen::Vector3d& centre, double scale) {
  TinMesh mesh = start;
  for (auto vh : mesh.vertices()) {
    mesh.set_point(vh, ToOpenMesh(centre + scale * (ToEigen(start.point(vh)) - centre)));
  }
  UpdateVertexNormals(&mesh);
  return mesh;
}

// The closed start before lifting: the visual hull, the given mesh or the hull of the
// inlier tie points remeshed to edge_length, else the fitted ellipsoid.
TinMesh UnliftedClosedMesh(const ClosedStart& start, const ClosedStartOptions& options, double edge_length) {
  TinMesh mesh;
  if (start.visual_hull) {
    std::vector<Eigen::Vector3d> points;
    std::vector<Eigen::Vector3i> triangles;
    MeshVisualHull(*start.visual_hull, edge_length, &points, &triangles);
    mesh = TinFromTriangles(points, triangles, "visual hull");
    QualityOptions quality;
    quality.target_edge_length = edge_length;
    QualityPass(&mesh, quality);
    UpdateVertexNormals(&mesh);
  } else if (start.given) {
    mesh = *start.given;
    QualityOptions quality;
    quality.target_edge_length = edge_length;
    QualityPass(&mesh, quality);
    UpdateVertexNormals(&mesh);
  } else if (!start.hull_points.empty()) {
    mesh = MakeHullMesh(start.hull_points, start.centre, edge_length, options.hull_inflate);
    QualityOptions quality;  // flat hull faces stretch the sphere's edges
    quality.target_edge_length = edge_length;
    QualityPass(&mesh, quality);
    UpdateVertexNormals(&mesh);
  } else {
    mesh = MakeEllipsoidMesh(start.fit->ellipsoid, edge_length);
  }
  return mesh;
}

// One scale of object lifting: sigma0 1e300 when no image sees the scaled start.
struct ScaleTrial {
  double scale, sigma0, mean_dn, scale_correction;
};

// One adjustment iteration of the start scaled by `scale` about `centre`: its sigma0,
// the mean normal displacement (m) and the median scale change the displacements ask for.
ScaleTrial TryScale(const TinMesh& mesh, const Eigen::Vector3d& centre, double scale,
                    const std::vector<LevelImage>& images, const AdjustmentOptions& one, LiftingTrial* trial) {
  TinMesh trial_mesh = Scaled(mesh, centre, scale);
  const TinMesh before = trial_mesh;
  trial->height = scale;
  double correction = 0.0;
  try {
    AdjustmentOptions single = one;
    single.max_iterations = 1;
    single.compute_precision = false;
    WindowAdjustment adjustment(&trial_mesh, images, single);
    const WindowReport report = adjustment.Run();
    double sum = 0.0;
    std::vector<double> corrections;
    for (auto vh : before.vertices()) {
      const Eigen::Vector3d n = ToEigen(before.normal(vh));
      const double dn = (ToEigen(trial_mesh.point(vh)) - ToEigen(before.point(vh))).dot(n);
      sum += dn;
      // The scale change that moves this vertex by dn along its normal.
      const Eigen::Vector3d radial = ToEigen(mesh.point(vh)) - centre;
      const double along = n.dot(radial);
      if (along > 0.2 * radial.norm()) corrections.push_back(dn / along);
    }
    trial->sigma0 = report.sigma0;
    trial->mean_dn = sum / before.n_vertices();
    trial->observations = report.observations;
    correction = Median(corrections);
  } catch (const std::runtime_error&) {
    trial->sigma0 = 1e300;  // no image sees this start: not a candidate
  }
  return {scale, trial->sigma0, trial->mean_dn, correction};
}

// The truth lies where the surface stops growing and starts shrinking; of such a pair
// the better fitting trial, else the best fitting trial overall (-1: none seen).
int BestScale(const std::vector<ScaleTrial>& tried) {
  int best = -1;
  for (size_t k = 0; k + 1 < tried.size(); ++k) {
    if (tried[k].sigma0 >= 1e300 || tried[k + 1].sigma0 >= 1e300) continue;
    if (!(tried[k].mean_dn > 0.0 && tried[k + 1].mean_dn < 0.0)) continue;
    const int better = tried[k].sigma0 <= tried[k + 1].sigma0 ? static_cast<int>(k) : static_cast<int>(k + 1);
    if (best < 0 || tried[better].sigma0 < tried[best].sigma0) best = better;
  }
  if (best < 0) {
    for (size_t k = 0; k < tried.size(); ++k) {
      if (tried[k].sigma0 < 1e300 && (best < 0 || tried[k].sigma0 < tried[best].sigma0)) best = static_cast<int>(k);
    }
  }
  return best;
}

// Vertex positions and normals, by vertex index.
void PointsAndNormals(const TinMesh& mesh, std::vector<Eigen::Vector3d>* points,
                      std::vector<Eigen::Vector3d>* normals) {
  for (auto vh : mesh.vertices()) {
    points->push_back(ToEigen(mesh.point(vh)));
    normals->push_back(ToEigen(mesh.normal(vh)));
  }
}

// Vertices whose position differs from `before`.
int CountMoved(const TinMesh& mesh, const std::vector<Eigen::Vector3d>& before) {
  int moved = 0;
  for (auto vh : mesh.vertices()) moved += ToEigen(mesh.point(vh)) != before[vh.idx()] ? 1 : 0;
  return moved;
}

}  // namespace

Eigen::Vector3d CameraAxesMeet(const ImageBlock& block) {
  if (block.images.size() < 2) throw std::runtime_error("the optical axes need at least 2 images to meet");
  Eigen::Matrix3d n = Eigen::Matrix3d::Zero();
  Eigen::Vector3d b = Eigen::Vector3d::Zero();
  for (const auto& image : block.images) {
    const Eigen::Vector3d d = image.cam_from_world.rotation.conjugate() * Eigen::Vector3d::UnitZ();
    const Eigen::Matrix3d m = Eigen::Matrix3d::Identity() - d * d.transpose();
    n += m;
    b += m * image.ProjectionCentre();
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(n);
  if (eig.eigenvalues()[0] < 1e-3 * eig.eigenvalues()[2]) {
    throw std::runtime_error("the optical axes are (nearly) parallel and meet nowhere");
  }
  return n.ldlt().solve(b);
}

EllipsoidFit FitStartEllipsoid(const std::vector<Eigen::Vector3d>& points,
                               const Eigen::Vector3d& centre_guess) {
  const size_t n = points.size();
  if (n < 10) {
    throw std::runtime_error("closed start: " + std::to_string(n) +
                             " tie points, at least 10 are needed to fit the start ellipsoid");
  }
  EllipsoidFit fit;
  fit.points = static_cast<int>(n);
  std::vector<double> distance(n);
  for (size_t i = 0; i < n; ++i) distance[i] = (points[i] - centre_guess).norm();
  StartShape shape{points, 0.0, Ellipsoid{}, true};
  shape.e.centre = centre_guess;
  shape.e.radii = Eigen::Vector3d::Constant(Median(distance));
  shape.size = shape.e.radii.x();
  ConcentrateOnClosestHalf(&shape);
  std::vector<double> r(n);
  const double s = TukeyRefit(&shape, &r);
  fit.ellipsoid = shape.e;
  fit.is_sphere = shape.is_sphere;
  double sum = 0.0;
  for (size_t i = 0; i < n; ++i) {
    if (TukeyWeight(r[i], s) <= 0.0) continue;
    ++fit.inliers;
    sum += r[i] * r[i];
  }
  if (fit.inliers < 10) {
    throw std::runtime_error("closed start: only " + std::to_string(fit.inliers) + " of " +
                             std::to_string(n) + " tie points fit one ellipsoid");
  }
  fit.rms_distance = std::sqrt(sum / fit.inliers);
  fit.inlier.resize(n);
  for (size_t i = 0; i < n; ++i) fit.inlier[i] = TukeyWeight(r[i], s) > 0.0;
  return fit;
}

void ClosedStartOptions::Check() const {
  if (shape != "ellipsoid" && shape != "hull" && shape != "visual-hull") {
    throw std::invalid_argument("closed start: shape must be ellipsoid, hull or visual-hull, not '" +
                                shape + "'");
  }
  visual_hull.Check();
  if (!(visual_hull_grow >= 0.0)) throw std::invalid_argument("closed start: visual_hull_grow must be >= 0");
  if (!(hull_inflate >= 0.0 && hull_inflate < 1.0)) {
    throw std::invalid_argument("closed start: hull_inflate must lie in [0, 1)");
  }
  if (!(constraint_voxel >= 0.0)) throw std::invalid_argument("closed start: constraint_voxel must be >= 0");
  if (!(hull_rim_edges >= 0.0)) throw std::invalid_argument("closed start: hull_rim_edges must be >= 0");
  if (!(hull_rim_cos >= 0.0 && hull_rim_cos <= 1.0)) {
    throw std::invalid_argument("closed start: hull_rim_cos must lie in [0, 1]");
  }
  if (lifting_steps < 0) throw std::invalid_argument("closed start: lifting_steps must be >= 0");
  if (lifting_steps > 0 && !(lifting_range > 0.0 && lifting_range < 1.8)) {
    throw std::invalid_argument("closed start: lifting_range (scale range) must lie in (0, 1.8)");
  }
}

std::string ClosedStart::Describe() const {
  std::ostringstream out;
  if (visual_hull) {
    out << "closed start: visual hull of " << visual_hull->Count() << " voxels of "
        << visual_hull->voxel << " m (grid " << visual_hull->size.transpose() << "), volume "
        << visual_hull->Volume() << ", centre " << centre.transpose();
    if (constraint_hull) {
      out << "; constraint hull of " << constraint_hull->Count() << " voxels of " << constraint_hull->voxel
          << " m, volume " << constraint_hull->Volume();
    }
  } else if (given) {
    out << "closed start from the given mesh: " << given->n_vertices() << " vertices, "
        << given->n_faces() << " faces, centre " << centre.transpose();
    if (given_repair.degenerate > 0) {
      out << "; " << given_repair.degenerate << " triangles of no area repaired (" << given_repair.flipped
          << " edge flips, " << given_repair.collapsed << " collapses)";
    }
  } else if (fit) {
    if (!hull_points.empty()) out << "convex hull of " << hull_points.size() << " tie points around the ";
    const Ellipsoid& e = fit->ellipsoid;
    out << "closed start: " << (fit->is_sphere ? "sphere" : "ellipsoid") << " centre "
        << e.centre.transpose() << ", radii " << e.radii.transpose() << " m, fitted to "
        << fit->inliers << " of " << fit->points << " tie points (rms " << fit->rms_distance << " m)";
  }
  return out.str();
}

ClosedStart PrepareClosedStart(const ImageBlock& block, const RegionOfInterest& roi,
                               const ClosedStartOptions& options) {
  options.Check();
  ClosedStart start;
  if (!options.mesh_file.empty()) {
    const MeshData data = ReadMesh(options.mesh_file);
    start.given = TinFromTriangles(data.vertices, data.faces, options.mesh_file);
    // A G1 patch over a triangle of no area is not finite (the first split or
    // tessellation would fail with a message that names no file).
    start.given_repair = RepairDegenerateTriangles(&*start.given);
    if (start.given_repair.left > 0) {
      throw std::runtime_error(options.mesh_file + ": " + std::to_string(start.given_repair.left) +
                               " triangles of no area (their corners on one line or one point) that "
                               "neither an edge flip nor a collapse removes");
    }
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (const auto& p : data.vertices) sum += p;
    start.centre = sum / static_cast<double>(data.vertices.size());
    return start;
  }
  if (options.shape == "visual-hull") {
    const Eigen::Vector3d grow = options.visual_hull_grow * (roi.max - roi.min);
    const Eigen::AlignedBox3d box(roi.min - grow, roi.max + grow);
    start.hull_views = ReadHullViews(block, options.visual_hull.foreground);
    const HullViews& views = *start.hull_views;
    start.visual_hull = CarveVisualHull(views.cameras, views.cam_from_world, views.masks, box, options.visual_hull);
    start.constraint_voxel = ChooseConstraintVoxel(block, box, options.constraint_voxel, start.visual_hull->voxel);
    if (start.constraint_voxel->voxel > 0.0) {
      VisualHullOptions fine = options.visual_hull;
      fine.voxel_size = start.constraint_voxel->voxel;
      start.constraint_hull = CarveVisualHull(views.cameras, views.cam_from_world, views.masks, box, fine);
    }
    if (!options.hull_rims) start.hull_views.reset();  // one byte per pixel and image: only the rims need them
    if (start.visual_hull->Count() == 0) {
      throw std::runtime_error(
          "closed start: no voxel of the region projects into the foreground of every image "
          "(check the background threshold)");
    }
    start.centre = start.visual_hull->Centroid();
    return start;
  }
  std::vector<Eigen::Vector3d> inside, all;
  for (const auto& p : block.points) {
    all.push_back(p.xyz);
    if (roi.Contains(p.xyz)) inside.push_back(p.xyz);
  }
  const std::vector<Eigen::Vector3d>& points = inside.size() >= 10 ? inside : all;
  Eigen::Vector3d guess;
  try {
    guess = CameraAxesMeet(block);
  } catch (const std::runtime_error&) {
    guess = 0.5 * (roi.min + roi.max);  // aerial-like blocks: the axes do not meet
  }
  start.fit = FitStartEllipsoid(points, guess);
  start.centre = start.fit->ellipsoid.centre;
  if (options.shape == "hull") {
    for (size_t i = 0; i < points.size(); ++i) {
      if (start.fit->inlier[i]) start.hull_points.push_back(points[i]);
    }
  }
  return start;
}

TinMesh MakeClosedStartMesh(const ClosedStart& start, const ClosedStartOptions& options,
                            double edge_length, const std::vector<LevelImage>& images,
                            const AdjustmentOptions& one, std::vector<LiftingTrial>* trials,
                            const std::function<void(const std::string&)>& say) {
  options.Check();
  const TinMesh mesh = UnliftedClosedMesh(start, options, edge_length);
  auto finish = [&](TinMesh result) {
    if (!options.write_start.empty()) {
      MeshData data;
      TinPointsAndTriangles(result, &data.vertices, &data.faces);
      WritePly(options.write_start, data);
    }
    return result;
  };
  if (options.lifting_steps == 0) return finish(mesh);

  // Object lifting along the normals: one iteration per scale factor.
  std::vector<ScaleTrial> tried;
  for (int k = 0; k < options.lifting_steps; ++k) {
    const double scale = 1.0 - 0.5 * options.lifting_range +
                         options.lifting_range * (options.lifting_steps == 1 ? 0.5 : k / (options.lifting_steps - 1.0));
    LiftingTrial trial;
    tried.push_back(TryScale(mesh, start.centre, scale, images, one, &trial));
    if (trials) trials->push_back(trial);
    if (say) {
      say("  lifting scale " + std::to_string(scale) + ": sigma0 " + std::to_string(trial.sigma0) +
          ", mean displacement " + std::to_string(trial.mean_dn) + " m");
    }
  }
  const int best = BestScale(tried);
  if (best < 0) throw std::runtime_error("object lifting: no scale of the closed start is seen by any image");
  const double scale = std::max(0.1, tried[best].scale + tried[best].scale_correction);
  if (say) say("  lifting: closed start scaled by " + std::to_string(scale));
  return finish(Scaled(mesh, start.centre, scale));
}

int ClampToVisualHull(const ClosedStart& start, double max_move, TinMesh* mesh, int* unresolved, bool guard) {
  if (unresolved) *unresolved = 0;
  if (!start.visual_hull) return 0;
  const HullOccupancy occupancy = SmoothHullOccupancy(*start.ConstraintHull());
  std::vector<Eigen::Vector3d> points, normals;
  PointsAndNormals(*mesh, &points, &normals);
  const std::vector<Eigen::Vector3d> before = points;
  int stuck = 0;
  PullInsideHull(occupancy, normals, max_move, &points, &stuck);
  // A spike farther out than max_move: to the centroid of its ring (mostly inside by
  // now), then pulled in from there; a few rounds for spikes of several vertices.
  for (int round = 0; round < 3 && stuck > 0; ++round) {
    std::vector<Eigen::Vector3d> spikes, directions;
    std::vector<int> index;
    for (auto vh : mesh->vertices()) {
      Eigen::Vector3d& p = points[vh.idx()];
      if (occupancy.Inside(p)) continue;
      Eigen::Vector3d sum = Eigen::Vector3d::Zero();
      int n = 0;
      for (auto nb : mesh->vv_range(vh)) {
        sum += points[nb.idx()];
        ++n;
      }
      if (n == 0) continue;
      p = sum / n;
      spikes.push_back(p);
      directions.push_back(normals[vh.idx()]);
      index.push_back(vh.idx());
    }
    PullInsideHull(occupancy, directions, max_move, &spikes, &stuck);
    for (size_t k = 0; k < index.size(); ++k) points[index[k]] = spikes[k];
  }
  if (unresolved) *unresolved = stuck;
  int moved = 0;
  for (size_t k = 0; k < points.size(); ++k) moved += points[k] != before[k] ? 1 : 0;
  if (moved > 0) {
    for (auto vh : mesh->vertices()) mesh->set_point(vh, ToOpenMesh(points[vh.idx()]));
    if (guard) {
      LimitFoldingSteps(mesh, before);
      moved = CountMoved(*mesh, before);
    }
    UpdateVertexNormals(mesh);
  }
  return moved;
}

int PushOntoVisualHullRims(const ClosedStart& start, double max_move, double max_cos, TinMesh* mesh) {
  if (!start.visual_hull || !start.hull_views) return 0;
  const HullOccupancy occupancy = SmoothHullOccupancy(*start.ConstraintHull());
  std::vector<Eigen::Vector3d> points, normals;
  PointsAndNormals(*mesh, &points, &normals);
  const std::vector<Eigen::Vector3d> before = points;
  if (PushOntoHullRims(occupancy, *start.hull_views, normals, max_move, max_cos, &points) == 0) return 0;
  for (auto vh : mesh->vertices()) mesh->set_point(vh, ToOpenMesh(points[vh.idx()]));
  // Pushes that fold a face or make two faces cross are halved and at last undone.
  LimitFoldingSteps(mesh, before);
  const int moved = CountMoved(*mesh, before);
  UpdateVertexNormals(mesh);
  return moved;
}

}  // namespace facets
