#include "scenes/evaluate.h"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Simple_cartesian.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <set>
#include <stdexcept>

#include "visibility/embree_scene.h"

namespace facets {
namespace {

using Kernel = CGAL::Simple_cartesian<double>;
using CgalTriangles = std::vector<Kernel::Triangle_3>;
using Primitive = CGAL::AABB_triangle_primitive<Kernel, CgalTriangles::const_iterator>;
using AabbTree = CGAL::AABB_tree<CGAL::AABB_traits<Kernel, Primitive>>;

// Exact point-to-mesh distance with the index of the closest face. Degenerate faces
// (zero area) are left out: they have no closest point of their own.
class MeshDistance {
 public:
  explicit MeshDistance(const MeshData& mesh) {
    triangles_.reserve(mesh.faces.size());
    for (size_t f = 0; f < mesh.faces.size(); ++f) {
      const Eigen::Vector3d& a = mesh.vertices[mesh.faces[f][0]];
      const Eigen::Vector3d& b = mesh.vertices[mesh.faces[f][1]];
      const Eigen::Vector3d& c = mesh.vertices[mesh.faces[f][2]];
      if ((b - a).cross(c - a).squaredNorm() <= 0.0) continue;
      triangles_.emplace_back(Kernel::Point_3(a.x(), a.y(), a.z()),
                              Kernel::Point_3(b.x(), b.y(), b.z()),
                              Kernel::Point_3(c.x(), c.y(), c.z()));
      face_of_.push_back(static_cast<int>(f));
    }
    if (triangles_.empty()) return;
    tree_.insert(triangles_.cbegin(), triangles_.cend());
    tree_.build();
    tree_.accelerate_distance_queries();
    // The first query builds the search structure: do it here, single-threaded, so
    // parallel queries afterwards only read.
    Closest(Eigen::Vector3d::Zero());
  }
  MeshDistance(const MeshDistance&) = delete;
  MeshDistance& operator=(const MeshDistance&) = delete;

  // Distance (m) and face index; (+inf, -1) for a mesh without triangles.
  std::pair<double, int> Closest(const Eigen::Vector3d& p) const {
    Eigen::Vector3d unused;
    return Closest(p, &unused);
  }
  // The same, and the closest point of the mesh itself in *closest.
  std::pair<double, int> Closest(const Eigen::Vector3d& p, Eigen::Vector3d* closest) const {
    if (triangles_.empty()) return {std::numeric_limits<double>::infinity(), -1};
    const Kernel::Point_3 query(p.x(), p.y(), p.z());
    const auto [point, primitive] = tree_.closest_point_and_primitive(query);
    const double d = std::sqrt(CGAL::squared_distance(query, point));
    *closest = Eigen::Vector3d(point.x(), point.y(), point.z());
    return {d, face_of_[primitive - triangles_.cbegin()]};
  }

 private:
  CgalTriangles triangles_;
  std::vector<int> face_of_;
  AabbTree tree_;
};

// How many images see a point of the truth surface: it projects inside the image, the
// ray meets its face at no more than the maximum view angle from the normal, and
// Embree's first hit along the ray (over the truth mesh) lies within the tolerance of
// the point. Shared by completeness (truth samples) and by the accuracy split (the
// closest truth point of each reconstruction sample), so both count views alike.
class TruthVisibility {
 public:
  TruthVisibility(const TruthScene& truth, const EvaluationOptions& options)
      : cos_max_angle_(std::cos(options.max_view_angle_deg * M_PI / 180.0)),
        tolerance_(options.visibility_tolerance_gsd * truth.ground_pixel_size) {
    face_normal_.resize(truth.mesh.faces.size());
    for (size_t f = 0; f < truth.mesh.faces.size(); ++f) {
      const auto& v = truth.mesh.vertices;
      const auto& t = truth.mesh.faces[f];
      face_normal_[f] = (v[t[1]] - v[t[0]]).cross(v[t[2]] - v[t[0]]).normalized();
    }
    if (truth.block.images.empty()) return;
    scene_ = std::make_unique<TriangleScene>(EmbreeDevice::Shared(), truth.mesh.vertices,
                                             truth.mesh.faces);
    for (const BlockImage& image : truth.block.images) {
      views_.push_back({image.ProjectionCentre(), &image, &truth.block.CameraOf(image)});
    }
  }

  // Images that see point p of truth face `face`.
  int Views(const Eigen::Vector3d& p, int face) const {
    int seen = 0;
    for (const View& view : views_) {
      const Eigen::Vector3d d = p - view.centre;
      const double length = d.norm();
      if (!(length > 0)) continue;
      if (std::abs(d.dot(face_normal_[face])) < cos_max_angle_ * length) continue;
      const Eigen::Vector3d point_in_cam = view.image->cam_from_world * p;
      if (!(point_in_cam.z() > 0)) continue;
      const Camera& camera = *view.camera;
      // Pinhole guard first: a strongly distorting model can fold a point far
      // outside the field of view back into the image.
      const double xp = camera.FocalX() * point_in_cam.x() / point_in_cam.z() + camera.PrincipalX();
      const double yp = camera.FocalY() * point_in_cam.y() / point_in_cam.z() + camera.PrincipalY();
      if (xp < -0.5 * camera.width || xp > 1.5 * camera.width || yp < -0.5 * camera.height ||
          yp > 1.5 * camera.height) {
        continue;
      }
      const Eigen::Vector2d pixel = camera.ImageFromCam(point_in_cam);
      if (!(pixel.x() >= 0 && pixel.x() <= camera.width && pixel.y() >= 0 &&
            pixel.y() <= camera.height)) {
        continue;
      }
      // Float rounding in Embree grows with the ray length: allow for it.
      const double slack = tolerance_ + 1e-6 * length;
      const RayHit hit = scene_->Intersect(view.centre, d, 0.0f,
                                           static_cast<float>(1.0 + slack / length));
      if (!hit.hit || (1.0 - static_cast<double>(hit.distance)) * length <= slack) ++seen;
    }
    return seen;
  }

 private:
  struct View {
    Eigen::Vector3d centre;
    const BlockImage* image;
    const Camera* camera;
  };
  double cos_max_angle_, tolerance_;
  std::vector<Eigen::Vector3d> face_normal_;
  std::unique_ptr<TriangleScene> scene_;
  std::vector<View> views_;
};

DistanceStats ComputeStats(std::vector<double> d) {
  DistanceStats s;
  s.count = d.size();
  if (d.empty()) return s;
  std::sort(d.begin(), d.end());
  double sum = 0, sum2 = 0;
  for (double x : d) {
    sum += x;
    sum2 += x * x;
  }
  const size_t n = d.size();
  s.mean = sum / n;
  s.rms = std::sqrt(sum2 / n);
  s.median = n % 2 ? d[n / 2] : 0.5 * (d[n / 2 - 1] + d[n / 2]);
  // Nearest-rank percentile: the smallest value with at least 90% at or below it.
  const size_t rank = static_cast<size_t>(std::ceil(0.9 * static_cast<double>(n)));
  s.p90 = d[std::max<size_t>(rank, 1) - 1];
  s.max = d.back();
  return s;
}

CompletenessStats ComputeCompleteness(const std::vector<double>& d,
                                      const std::vector<double>& thresholds_m) {
  CompletenessStats c;
  c.count = d.size();
  c.within.assign(thresholds_m.size(), 0.0);
  if (d.empty()) return c;
  for (size_t t = 0; t < thresholds_m.size(); ++t) {
    const size_t hits = std::count_if(d.begin(), d.end(),
                                      [&](double x) { return x <= thresholds_m[t]; });
    c.within[t] = static_cast<double>(hits) / static_cast<double>(d.size());
  }
  return c;
}

std::string DefaultLabelName(int label) {
  switch (label) {
    case 0: return "ground";
    case 1: return "roof";
    case 2: return "wall";
    case 3: return "object";
    default: return "label" + std::to_string(label);
  }
}

double MeshArea(const MeshData& mesh, const std::vector<bool>& mask) {
  double area = 0;
  for (size_t i = 0; i < mesh.faces.size(); ++i) {
    if (!mask[i]) continue;
    const Eigen::Vector3i& f = mesh.faces[i];
    area += 0.5 * (mesh.vertices[f[1]] - mesh.vertices[f[0]])
                      .cross(mesh.vertices[f[2]] - mesh.vertices[f[0]])
                      .norm();
  }
  return area;
}

// The spacing SampleSurface must use so that `mesh` gets at most max_samples.
double EffectiveSpacing(const MeshData& mesh, const std::vector<bool>& mask, double spacing,
                        size_t max_samples) {
  const double area = MeshArea(mesh, mask);
  if (area / (spacing * spacing) > static_cast<double>(max_samples)) {
    return std::sqrt(area / static_cast<double>(max_samples));
  }
  return spacing;
}

// Faces whose bounding box meets the region of interest (all faces without one): only
// those are sampled, so a large terrain around a small ROI neither costs time nor
// coarsens the spacing.
std::vector<bool> FacesInRoi(const MeshData& mesh, const std::optional<RegionOfInterest>& roi) {
  std::vector<bool> mask(mesh.faces.size(), true);
  if (!roi) return mask;
  for (size_t i = 0; i < mesh.faces.size(); ++i) {
    Eigen::Vector3d lo = mesh.vertices[mesh.faces[i][0]], hi = lo;
    for (int c = 1; c < 3; ++c) {
      lo = lo.cwiseMin(mesh.vertices[mesh.faces[i][c]]);
      hi = hi.cwiseMax(mesh.vertices[mesh.faces[i][c]]);
    }
    mask[i] = (hi.array() >= roi->min.array()).all() && (lo.array() <= roi->max.array()).all();
  }
  return mask;
}

int LabelOf(const MeshData& mesh, int face) {
  return mesh.face_labels.empty() || face < 0 ? 0 : mesh.face_labels[face];
}

bool InRoi(const std::optional<RegionOfInterest>& roi, const Eigen::Vector3d& p) {
  return !roi || roi->Contains(p);
}

std::string RegionName(const TruthScene& truth, int label) {
  const auto name = truth.labels.find(label);
  return name != truth.labels.end() ? name->second : DefaultLabelName(label);
}

// Distances (m) of the reconstruction's samples to the truth, by the region label of
// the closest truth face, and split by the images that see the closest truth point
// (>= 2 or < 2).
struct AccuracyDistances {
  std::map<int, std::vector<double>> by_label, multi_view, few_views;
  std::vector<double> all, multi_view_all, few_views_all;
};

// Reported sigma (m) of the reconstruction's vertices inside the ROI by the region of
// the closest truth face and by their view count (< 2, 2, >= 3): is a wall seen by
// fewer images less certain? Vertices with sigma 0 (fixed or not estimated) are left out.
std::vector<SigmaByViews> SigmaByViewCount(const TruthScene& truth, const MeshData& reconstruction,
                                           const MeshDistance& to_truth,
                                           const std::optional<RegionOfInterest>& roi) {
  std::map<int, std::array<std::vector<double>, 3>> by_label;
  for (size_t v = 0; v < reconstruction.vertices.size(); ++v) {
    if (!InRoi(roi, reconstruction.vertices[v])) continue;
    const int label = LabelOf(truth.mesh, to_truth.Closest(reconstruction.vertices[v]).second);
    const int views = reconstruction.views[v];
    if (!(reconstruction.sigma[v] > 0)) continue;
    by_label[label][views < 2 ? 0 : views == 2 ? 1 : 2].push_back(reconstruction.sigma[v]);
  }
  std::vector<SigmaByViews> rows;
  for (auto& [label, groups] : by_label) {
    SigmaByViews row;
    row.label = label;
    row.name = RegionName(truth, label);
    for (int g = 0; g < 3; ++g) {
      const DistanceStats st = ComputeStats(groups[g]);
      row.count[g] = st.count;
      row.median[g] = st.median;
      row.mean[g] = st.mean;
    }
    rows.push_back(row);
  }
  return rows;
}

// Accuracy: reconstruction samples inside the ROI -> truth mesh, each also split by
// the views of its closest truth point (walls seen by >= 2 images are the ones the
// images can fix; a drape hanging before a wall no two images see is not one of them).
// Sets the report's sample count and, when the mesh has sigma and views, its sigma rows.
AccuracyDistances MeasureAccuracy(const TruthScene& truth, const MeshData& reconstruction,
                                  const std::vector<bool>& reconstruction_mask,
                                  const TruthVisibility& visibility, EvaluationReport* report) {
  const MeshDistance to_truth(truth.mesh);
  std::vector<Eigen::Vector3d> samples =
      SampleSurface(reconstruction, report->sample_spacing, nullptr, &reconstruction_mask);
  samples.erase(std::remove_if(samples.begin(), samples.end(),
                               [&](const Eigen::Vector3d& p) { return !InRoi(report->roi, p); }),
                samples.end());
  std::vector<double> distance(samples.size());
  std::vector<int> label(samples.size()), views(samples.size());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, samples.size()),
                    [&](const tbb::blocked_range<size_t>& r) {
                      for (size_t i = r.begin(); i != r.end(); ++i) {
                        Eigen::Vector3d closest;
                        const auto [d, face] = to_truth.Closest(samples[i], &closest);
                        distance[i] = d;
                        label[i] = LabelOf(truth.mesh, face);
                        views[i] = face >= 0 ? visibility.Views(closest, face) : 0;
                      }
                    });
  report->num_reconstruction_samples = samples.size();
  if (!reconstruction.sigma.empty() &&
      reconstruction.views.size() == reconstruction.vertices.size()) {
    report->sigma_by_views = SigmaByViewCount(truth, reconstruction, to_truth, report->roi);
  }
  AccuracyDistances accuracy;
  for (size_t i = 0; i < samples.size(); ++i) {
    accuracy.by_label[label[i]].push_back(distance[i]);
    (views[i] >= 2 ? accuracy.multi_view : accuracy.few_views)[label[i]].push_back(distance[i]);
    (views[i] >= 2 ? accuracy.multi_view_all : accuracy.few_views_all).push_back(distance[i]);
  }
  accuracy.all = distance;
  return accuracy;
}

// Completeness samples: every truth sample inside the ROI with its region label, the
// images that see it and its distance (m) to the reconstruction.
void MeasureCompleteness(const TruthScene& truth, const MeshData& reconstruction,
                         const std::vector<bool>& truth_mask, const TruthVisibility& visibility,
                         EvaluationReport* report) {
  std::vector<int> face_of;
  std::vector<Eigen::Vector3d> points =
      SampleSurface(truth.mesh, report->truth_sample_spacing, &face_of, &truth_mask);
  std::vector<TruthSample>& samples = report->truth_samples;
  samples.reserve(points.size());
  for (size_t i = 0; i < points.size(); ++i) {
    if (!InRoi(report->roi, points[i])) continue;
    TruthSample s;
    s.point = points[i];
    s.label = face_of[i];  // face index for now, label below
    samples.push_back(s);
  }
  const MeshDistance to_reconstruction(reconstruction);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, samples.size()),
                    [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i != r.end(); ++i) {
      TruthSample& s = samples[i];
      const int face = s.label;
      const Eigen::Vector3d& p = s.point;
      s.views = visibility.Views(p, face);
      s.label = LabelOf(truth.mesh, face);
      s.distance = to_reconstruction.Closest(p).first;
    }
  });
  report->num_truth_samples = samples.size();
}

// One row per region label present in the truth or the accuracy samples, then the row
// over all regions (label -1); completeness counts truth samples seen by >= min_views.
void AddRegionRows(const TruthScene& truth, const EvaluationOptions& options,
                   AccuracyDistances* accuracy, EvaluationReport* report) {
  const double gsd = truth.ground_pixel_size;
  std::vector<double> thresholds_m;
  for (double t : options.completeness_thresholds_gsd) thresholds_m.push_back(t * gsd);
  std::map<int, std::vector<double>> seen_d, multi_d, few_d;
  std::vector<double> seen_all, multi_all, few_all;
  std::set<int> labels_present;
  for (const auto& [label, d] : accuracy->by_label) labels_present.insert(label);
  for (int l : truth.mesh.face_labels) labels_present.insert(l);
  if (truth.mesh.face_labels.empty()) labels_present.insert(0);
  for (const TruthSample& s : report->truth_samples) {
    if (s.views < options.min_views) continue;
    ++report->num_truth_samples_seen;
    seen_d[s.label].push_back(s.distance);
    seen_all.push_back(s.distance);
    (s.views >= 2 ? multi_d : few_d)[s.label].push_back(s.distance);
    (s.views >= 2 ? multi_all : few_all).push_back(s.distance);
  }
  for (int label : labels_present) {
    RegionScore row;
    row.label = label;
    row.name = RegionName(truth, label);
    row.accuracy = ComputeStats(accuracy->by_label[label]);
    row.accuracy_multi_view = ComputeStats(accuracy->multi_view[label]);
    row.accuracy_few_views = ComputeStats(accuracy->few_views[label]);
    row.completeness = ComputeCompleteness(seen_d[label], thresholds_m);
    row.multi_view = ComputeCompleteness(multi_d[label], thresholds_m);
    row.few_views = ComputeCompleteness(few_d[label], thresholds_m);
    report->regions.push_back(row);
  }
  RegionScore all;
  all.label = -1;
  all.name = "all";
  all.accuracy = ComputeStats(accuracy->all);
  all.accuracy_multi_view = ComputeStats(accuracy->multi_view_all);
  all.accuracy_few_views = ComputeStats(accuracy->few_views_all);
  all.completeness = ComputeCompleteness(seen_all, thresholds_m);
  all.multi_view = ComputeCompleteness(multi_all, thresholds_m);
  all.few_views = ComputeCompleteness(few_all, thresholds_m);
  report->regions.push_back(all);
}

}  // namespace

void EvaluationOptions::Check() const {
  auto fail = [](const std::string& what) {
    throw std::invalid_argument("EvaluationOptions: " + what);
  };
  if (!(sample_spacing_gsd > 0) || !std::isfinite(sample_spacing_gsd))
    fail("sample_spacing_gsd must be > 0");
  if (max_samples < 1) fail("max_samples must be >= 1");
  if (!(visibility_tolerance_gsd >= 0) || !std::isfinite(visibility_tolerance_gsd))
    fail("visibility_tolerance_gsd must be >= 0");
  if (!(max_view_angle_deg > 0 && max_view_angle_deg <= 90))
    fail("max_view_angle_deg must be in (0, 90]");
  if (min_views < 0) fail("min_views must be >= 0");
  if (completeness_thresholds_gsd.empty()) fail("completeness_thresholds_gsd is empty");
  for (double t : completeness_thresholds_gsd)
    if (!(t > 0) || !std::isfinite(t)) fail("completeness thresholds must be > 0");
  if (roi && !(roi->min.array() <= roi->max.array()).all()) fail("roi min > max");
}

std::vector<Eigen::Vector3d> SampleSurface(const MeshData& mesh, double spacing,
                                           std::vector<int>* face_of,
                                           const std::vector<bool>* face_mask) {
  if (!(spacing > 0)) throw std::invalid_argument("SampleSurface: spacing must be > 0");
  // R2 sequence (Roberts 2018): the plastic-number generalisation of the golden ratio,
  // well spread for any count; folded into the triangle by reflection.
  constexpr double kA1 = 0.7548776662466927;
  constexpr double kA2 = 0.5698402909980532;
  const double cell = spacing * spacing;
  std::vector<Eigen::Vector3d> samples;
  if (face_of) face_of->clear();
  long double cumulative = 0;
  long long emitted = 0;
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    if (face_mask && !(*face_mask)[f]) continue;
    const Eigen::Vector3d& a = mesh.vertices[mesh.faces[f][0]];
    const Eigen::Vector3d ab = mesh.vertices[mesh.faces[f][1]] - a;
    const Eigen::Vector3d ac = mesh.vertices[mesh.faces[f][2]] - a;
    cumulative += 0.5L * ab.cross(ac).norm();
    // The nudge keeps an area that is an exact multiple of the cell (1037 m^2 at 0.1 m)
    // from losing its last sample to the rounding of the running sum.
    const long long target =
        static_cast<long long>(std::floor(cumulative / cell * (1.0L + 1e-12L)));
    for (; emitted < target; ++emitted) {
      double u = std::fmod(0.5 + kA1 * static_cast<double>(emitted), 1.0);
      double v = std::fmod(0.5 + kA2 * static_cast<double>(emitted), 1.0);
      if (u + v > 1.0) {
        u = 1.0 - u;
        v = 1.0 - v;
      }
      samples.push_back(a + u * ab + v * ac);
      if (face_of) face_of->push_back(static_cast<int>(f));
    }
  }
  return samples;
}

EvaluationReport Evaluate(const TruthScene& truth, const MeshData& reconstruction,
                          const EvaluationOptions& options) {
  options.Check();
  truth.mesh.Check("truth mesh");
  reconstruction.Check("reconstruction");
  if (!(truth.ground_pixel_size > 0)) {
    throw std::invalid_argument("Evaluate: truth ground_pixel_size must be > 0");
  }
  const double gsd = truth.ground_pixel_size;
  EvaluationReport report;
  report.ground_pixel_size = gsd;
  report.mesh_crossings = CountCrossingTriangles(reconstruction.vertices, reconstruction.faces);
  report.thresholds_gsd = options.completeness_thresholds_gsd;
  report.num_images = truth.block.images.size();
  report.roi = options.roi ? options.roi : truth.roi;

  const double spacing = options.sample_spacing_gsd * gsd;
  const std::vector<bool> reconstruction_mask = FacesInRoi(reconstruction, report.roi);
  const std::vector<bool> truth_mask = FacesInRoi(truth.mesh, report.roi);
  report.sample_spacing =
      EffectiveSpacing(reconstruction, reconstruction_mask, spacing, options.max_samples);
  report.truth_sample_spacing =
      EffectiveSpacing(truth.mesh, truth_mask, spacing, options.max_samples);

  const TruthVisibility visibility(truth, options);
  AccuracyDistances accuracy =
      MeasureAccuracy(truth, reconstruction, reconstruction_mask, visibility, &report);
  MeasureCompleteness(truth, reconstruction, truth_mask, visibility, &report);
  AddRegionRows(truth, options, &accuracy, &report);
  report.leaning_walls =
      EvaluateLeaningWalls(truth, reconstruction, report.roi, options.wall_band_gsd * gsd);
  if (options.height_grid_gsd > 0.0 && report.roi) {
    report.heights = EvaluateHeights(truth.mesh, reconstruction, *report.roi,
                                     options.height_grid_gsd * gsd, options.height_border_gsd * gsd);
  }
  return report;
}

EvaluationReport EvaluateFiles(const std::string& truth_dir, const std::string& mesh_path,
                               const EvaluationOptions& options) {
  const TruthScene truth = ReadTruthScene(truth_dir);
  const MeshData mesh = ReadMesh(mesh_path);
  // Without faces every distance would be missing, and the accuracy of nothing reads as
  // an rms of 0.
  if (mesh.faces.empty()) {
    throw std::runtime_error(mesh_path + ": has no faces (" + std::to_string(mesh.vertices.size()) +
                             " vertices): nothing to evaluate");
  }
  EvaluationReport report = Evaluate(truth, mesh, options);
  report.truth_name = truth_dir;
  report.mesh_name = mesh_path;
  return report;
}


}  // namespace facets
