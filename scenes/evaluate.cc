#include "scenes/evaluate.h"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Simple_cartesian.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <numeric>
#include <set>
#include <sstream>
#include <stdexcept>

#include "io/colmap_io.h"
#include "mesh/principal_axes.h"
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

nlohmann::json StatsJson(const DistanceStats& s, double gsd) {
  auto block = [&](double scale) {
    return nlohmann::json{{"mean", s.mean * scale},     {"median", s.median * scale},
                          {"rms", s.rms * scale},       {"p90", s.p90 * scale},
                          {"max", s.max * scale}};
  };
  return {{"count", s.count}, {"metres", block(1.0)}, {"gsd", block(1.0 / gsd)}};
}

nlohmann::json CompletenessJson(const CompletenessStats& c, const std::vector<double>& t) {
  nlohmann::json within = nlohmann::json::object();
  for (size_t i = 0; i < t.size() && i < c.within.size(); ++i) {
    char key[32];
    std::snprintf(key, sizeof(key), "%g", t[i]);
    within[key] = c.within[i];
  }
  return {{"count", c.count}, {"within_gsd", within}};
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

TruthScene ReadTruthScene(const std::string& dir) {
  namespace fs = std::filesystem;
  TruthScene truth;
  const fs::path root(dir);
  if (!fs::is_directory(root)) throw std::runtime_error(dir + ": truth folder does not exist");

  const std::string json_path = (root / "truth.json").string();
  std::ifstream json_in(json_path);
  if (!json_in) throw std::runtime_error(json_path + ": cannot open");
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(json_in);
  } catch (const nlohmann::json::exception& e) {
    throw std::runtime_error(json_path + ": not valid JSON: " + e.what());
  }
  try {
    if (!j.contains("ground_pixel_size")) {
      throw std::runtime_error(json_path + ": missing \"ground_pixel_size\"");
    }
    truth.ground_pixel_size = j.at("ground_pixel_size").get<double>();
    if (!(truth.ground_pixel_size > 0) || !std::isfinite(truth.ground_pixel_size)) {
      throw std::runtime_error(json_path + ": \"ground_pixel_size\" must be > 0");
    }
    if (j.contains("region_of_interest") && !j["region_of_interest"].is_null()) {
      const auto& r = j["region_of_interest"];
      RegionOfInterest roi;
      const auto lo = r.at("min").get<std::vector<double>>();
      const auto hi = r.at("max").get<std::vector<double>>();
      if (lo.size() != 3 || hi.size() != 3) {
        throw std::runtime_error(json_path + ": region_of_interest min/max need 3 values");
      }
      roi.min = Eigen::Vector3d(lo[0], lo[1], lo[2]);
      roi.max = Eigen::Vector3d(hi[0], hi[1], hi[2]);
      if (!roi.min.allFinite() || !roi.max.allFinite() ||
          !(roi.min.array() <= roi.max.array()).all()) {
        throw std::runtime_error(json_path + ": region_of_interest is empty or not finite");
      }
      truth.roi = roi;
    }
    if (j.contains("shapes") && j["shapes"].is_array()) {
      for (const auto& shape : j["shapes"]) {
        if (shape.value("type", "") != "building") continue;
        TruthBuilding b;
        const auto c = shape.value("centre", std::vector<double>{0, 0, 0});
        if (c.size() != 3) throw std::runtime_error(json_path + ": building centre needs 3 values");
        b.centre = Eigen::Vector3d(c[0], c[1], c[2]);
        b.azimuth_deg = shape.value("azimuth_deg", 0.0);
        b.length = shape.value("length", 10.0);
        b.width = shape.value("width", 10.0);
        b.height = shape.value("height", 3.0);
        const auto lean = shape.value("wall_lean_deg", std::vector<double>{0, 0, 0, 0});
        if (lean.size() != 4) throw std::runtime_error(json_path + ": wall_lean_deg needs 4 values");
        b.wall_lean_deg = Eigen::Vector4d(lean[0], lean[1], lean[2], lean[3]);
        truth.buildings.push_back(b);
      }
    }
    if (j.contains("labels")) {
      for (const auto& [key, value] : j["labels"].items()) {
        int label = 0;
        try {
          size_t used = 0;
          label = std::stoi(key, &used);
          if (used != key.size()) throw std::invalid_argument(key);
        } catch (const std::exception&) {
          throw std::runtime_error(json_path + ": label key '" + key + "' is not an integer");
        }
        truth.labels[label] = value.get<std::string>();
      }
    }
  } catch (const nlohmann::json::exception& e) {
    throw std::runtime_error(json_path + ": " + e.what());
  }

  const fs::path ply = root / "truth.ply";
  const fs::path obj = root / "truth.obj";
  truth.mesh = fs::exists(ply) || !fs::exists(obj) ? ReadPly(ply.string()) : ReadObj(obj.string());
  truth.block = ReadColmapModel((root / "sparse").string());
  return truth;
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
  const auto in_roi = [&](const Eigen::Vector3d& p) { return !report.roi || report.roi->Contains(p); };

  const double spacing = options.sample_spacing_gsd * gsd;
  const std::vector<bool> reconstruction_mask = FacesInRoi(reconstruction, report.roi);
  const std::vector<bool> truth_mask = FacesInRoi(truth.mesh, report.roi);
  report.sample_spacing =
      EffectiveSpacing(reconstruction, reconstruction_mask, spacing, options.max_samples);
  report.truth_sample_spacing =
      EffectiveSpacing(truth.mesh, truth_mask, spacing, options.max_samples);

  const TruthVisibility visibility(truth, options);

  // --- Accuracy: reconstruction samples -> truth mesh; also split by the views of each
  // sample's closest truth point (issue 7 asks for the accuracy of walls seen by >= 2
  // images; a drape hanging before a wall no two images see is not one of them).
  std::map<int, std::vector<double>> accuracy;  // label -> distances
  std::map<int, std::vector<double>> accuracy_multi, accuracy_few;
  std::vector<double> accuracy_all, accuracy_multi_all, accuracy_few_all;
  {
    const MeshDistance to_truth(truth.mesh);
    std::vector<Eigen::Vector3d> samples =
        SampleSurface(reconstruction, report.sample_spacing, nullptr, &reconstruction_mask);
    samples.erase(std::remove_if(samples.begin(), samples.end(),
                                 [&](const Eigen::Vector3d& p) { return !in_roi(p); }),
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
    report.num_reconstruction_samples = samples.size();
    if (!reconstruction.sigma.empty() && reconstruction.views.size() == reconstruction.vertices.size()) {
      // Sigma by view count per region: is a wall seen by fewer images less certain?
      std::map<int, std::array<std::vector<double>, 3>> by_label;
      for (size_t v = 0; v < reconstruction.vertices.size(); ++v) {
        if (!in_roi(reconstruction.vertices[v])) continue;
        const int label = LabelOf(truth.mesh, to_truth.Closest(reconstruction.vertices[v]).second);
        const int views = reconstruction.views[v];
        if (!(reconstruction.sigma[v] > 0)) continue;  // fixed or not estimated
        by_label[label][views < 2 ? 0 : views == 2 ? 1 : 2].push_back(reconstruction.sigma[v]);
      }
      for (auto& [label, groups] : by_label) {
        SigmaByViews row;
        row.label = label;
        const auto name = truth.labels.find(label);
        row.name = name != truth.labels.end() ? name->second : DefaultLabelName(label);
        for (int g = 0; g < 3; ++g) {
          const DistanceStats st = ComputeStats(groups[g]);
          row.count[g] = st.count;
          row.median[g] = st.median;
          row.mean[g] = st.mean;
        }
        report.sigma_by_views.push_back(row);
      }
    }
    for (size_t i = 0; i < samples.size(); ++i) {
      accuracy[label[i]].push_back(distance[i]);
      (views[i] >= 2 ? accuracy_multi : accuracy_few)[label[i]].push_back(distance[i]);
      (views[i] >= 2 ? accuracy_multi_all : accuracy_few_all).push_back(distance[i]);
    }
    accuracy_all = distance;
  }

  // --- Completeness: truth samples seen by the cameras -> reconstruction.
  {
    std::vector<int> face_of;
    std::vector<Eigen::Vector3d> points =
        SampleSurface(truth.mesh, report.truth_sample_spacing, &face_of, &truth_mask);
    std::vector<TruthSample>& samples = report.truth_samples;
    samples.reserve(points.size());
    for (size_t i = 0; i < points.size(); ++i) {
      if (!in_roi(points[i])) continue;
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
    report.num_truth_samples = samples.size();
  }

  // --- Per-region rows.
  std::vector<double> thresholds_m;
  for (double t : options.completeness_thresholds_gsd) thresholds_m.push_back(t * gsd);
  std::map<int, std::vector<double>> seen_d, multi_d, few_d;
  std::vector<double> seen_all, multi_all, few_all;
  std::set<int> labels_present;
  for (const auto& [label, d] : accuracy) labels_present.insert(label);
  for (int l : truth.mesh.face_labels) labels_present.insert(l);
  if (truth.mesh.face_labels.empty()) labels_present.insert(0);
  for (const TruthSample& s : report.truth_samples) {
    if (s.views < options.min_views) continue;
    ++report.num_truth_samples_seen;
    seen_d[s.label].push_back(s.distance);
    seen_all.push_back(s.distance);
    (s.views >= 2 ? multi_d : few_d)[s.label].push_back(s.distance);
    (s.views >= 2 ? multi_all : few_all).push_back(s.distance);
  }
  for (int label : labels_present) {
    RegionScore row;
    row.label = label;
    const auto name = truth.labels.find(label);
    row.name = name != truth.labels.end() ? name->second : DefaultLabelName(label);
    row.accuracy = ComputeStats(accuracy[label]);
    row.accuracy_multi_view = ComputeStats(accuracy_multi[label]);
    row.accuracy_few_views = ComputeStats(accuracy_few[label]);
    row.completeness = ComputeCompleteness(seen_d[label], thresholds_m);
    row.multi_view = ComputeCompleteness(multi_d[label], thresholds_m);
    row.few_views = ComputeCompleteness(few_d[label], thresholds_m);
    report.regions.push_back(row);
  }
  RegionScore all;
  all.label = -1;
  all.name = "all";
  all.accuracy = ComputeStats(accuracy_all);
  all.accuracy_multi_view = ComputeStats(accuracy_multi_all);
  all.accuracy_few_views = ComputeStats(accuracy_few_all);
  all.completeness = ComputeCompleteness(seen_all, thresholds_m);
  all.multi_view = ComputeCompleteness(multi_all, thresholds_m);
  all.few_views = ComputeCompleteness(few_all, thresholds_m);
  report.regions.push_back(all);
  report.leaning_walls =
      EvaluateLeaningWalls(truth, reconstruction, report.roi, options.wall_band_gsd * gsd);
  if (options.height_grid_gsd > 0.0 && report.roi) {
    report.heights = EvaluateHeights(truth.mesh, reconstruction, *report.roi,
                                     options.height_grid_gsd * gsd, options.height_border_gsd * gsd);
  }
  return report;
}

std::vector<WallLean> EvaluateLeaningWalls(const TruthScene& truth, const MeshData& reconstruction,
                                           const std::optional<RegionOfInterest>& roi, double band) {
  std::vector<WallLean> result;
  const double deg = M_PI / 180.0;
  const Eigen::Vector2d sides[4] = {{1, 0}, {0, 1}, {-1, 0}, {0, -1}};
  const auto& tv = truth.mesh.vertices;
  for (size_t bi = 0; bi < truth.buildings.size(); ++bi) {
    const TruthBuilding& b = truth.buildings[bi];
    const double ca = std::cos(b.azimuth_deg * deg), sa = std::sin(b.azimuth_deg * deg);
    for (int w = 0; w < 4; ++w) {
      if (b.wall_lean_deg[w] == 0.0) continue;
      const Eigen::Vector3d out(ca * sides[w].x() - sa * sides[w].y(), sa * sides[w].x() + ca * sides[w].y(), 0);
      const double lean = b.wall_lean_deg[w] * deg;
      // Outward lean: the top moves out, so the outward normal looks down.
      const Eigen::Vector3d expected = std::cos(lean) * out - std::sin(lean) * Eigen::Vector3d::UnitZ();
      const double reach = 0.75 * std::hypot(b.length, b.width) + b.height;
      std::vector<Eigen::Vector3d> wall_points;
      for (size_t f = 0; f < truth.mesh.faces.size(); ++f) {
        if (LabelOf(truth.mesh, static_cast<int>(f)) != 2) continue;
        const auto& t = truth.mesh.faces[f];
        const Eigen::Vector3d n = (tv[t[1]] - tv[t[0]]).cross(tv[t[2]] - tv[t[0]]).normalized();
        const Eigen::Vector3d centroid = (tv[t[0]] + tv[t[1]] + tv[t[2]]) / 3.0;
        if (n.dot(expected) < std::cos(2 * deg) || (centroid - b.centre).head<2>().norm() > reach) continue;
        for (int k = 0; k < 3; ++k) wall_points.push_back(tv[t[k]]);
      }
      if (wall_points.size() < 3) continue;
      WallLean lean_row;
      lean_row.building = static_cast<int>(bi);
      lean_row.wall = w;
      lean_row.true_lean_deg = b.wall_lean_deg[w];
      auto signed_lean = [&](const PlaneFit& fit) {
        const Eigen::Vector3d n = fit.normal.dot(out) < 0 ? Eigen::Vector3d(-fit.normal) : fit.normal;
        return std::asin(std::clamp(-n.z(), -1.0, 1.0)) / deg;
      };
      const PlaneFit truth_fit = FitPlane(wall_points);
      lean_row.truth_fit_lean_deg = signed_lean(truth_fit);
      const Eigen::Vector3d along = Eigen::Vector3d::UnitZ().cross(out);
      double s_min = 1e300, s_max = -1e300, eave = -1e300;
      for (const auto& p : wall_points) {
        s_min = std::min(s_min, p.dot(along));
        s_max = std::max(s_max, p.dot(along));
        eave = std::max(eave, p.z());
      }
      const double foot = eave - b.height;
      std::vector<Eigen::Vector3d> near;
      for (const auto& p : reconstruction.vertices) {
        if (roi && !roi->Contains(p)) continue;
        const double s = p.dot(along);
        if (s < s_min + 1.0 || s > s_max - 1.0) continue;
        if (p.z() < foot + 0.15 * b.height || p.z() > eave - 0.15 * b.height) continue;
        if (std::abs((p - truth_fit.centroid).dot(truth_fit.normal)) > band) continue;
        near.push_back(p);
      }
      lean_row.lean_deg = std::numeric_limits<double>::quiet_NaN();
      if (near.size() >= 10) {
        try {
          PlaneFit fit = FitPlane(near);
          // One robust round: points beyond 2.5 rms (a roof or ground patch in the band)
          // are left out and the plane fitted again.
          std::vector<Eigen::Vector3d> kept;
          for (const auto& p : near) {
            if (std::abs((p - fit.centroid).dot(fit.normal)) <= 2.5 * fit.rms) kept.push_back(p);
          }
          if (kept.size() >= 10) fit = FitPlane(kept);
          lean_row.lean_deg = signed_lean(fit);
          lean_row.vertices = static_cast<int>(kept.size() >= 10 ? kept.size() : near.size());
          lean_row.rms = fit.rms;
        } catch (const std::invalid_argument&) {
          // Collinear vertices: no plane, lean stays NaN.
        }
      }
      if (roi && near.empty() && !roi->Contains(truth_fit.centroid)) continue;  // wall outside the region
      result.push_back(lean_row);
    }
  }
  return result;
}

HeightErrors EvaluateHeights(const MeshData& truth, const MeshData& reconstruction,
                             const RegionOfInterest& roi, double spacing, double border) {
  HeightErrors h;
  h.spacing = spacing;
  const TriangleScene truth_scene(EmbreeDevice::Shared(), truth.vertices, truth.faces);
  const TriangleScene rec_scene(EmbreeDevice::Shared(), reconstruction.vertices, reconstruction.faces);
  // Rays start above everything: the highest point wins, as in a DSM.
  double top = roi.max.z();
  for (const auto& v : truth.vertices) top = std::max(top, v.z());
  for (const auto& v : reconstruction.vertices) top = std::max(top, v.z());
  top += 10.0;
  const Eigen::Vector3d down(0, 0, -1);
  double sum = 0, sum2 = 0;
  h.min = 1e300;
  h.max = -1e300;
  for (double y = roi.min.y() + border; y <= roi.max.y() - border + 1e-9; y += spacing) {
    for (double x = roi.min.x() + border; x <= roi.max.x() - border + 1e-9; x += spacing) {
      const Eigen::Vector3d origin(x, y, top);
      const RayHit t = truth_scene.Intersect(origin, down);
      if (!t.hit) continue;
      const RayHit r = rec_scene.Intersect(origin, down);
      if (!r.hit) {
        ++h.missing;
        continue;
      }
      // Embree's float distances are exact enough for centimetres at tens of metres.
      const double dz = static_cast<double>(t.distance) - static_cast<double>(r.distance);
      sum += dz;
      sum2 += dz * dz;
      h.min = std::min(h.min, dz);
      h.max = std::max(h.max, dz);
      ++h.count;
    }
  }
  if (h.count > 0) {
    h.mean = sum / h.count;
    h.rms = std::sqrt(sum2 / h.count);
  } else {
    h.min = h.max = 0;
  }
  return h;
}

EvaluationReport EvaluateFiles(const std::string& truth_dir, const std::string& mesh_path,
                               const EvaluationOptions& options) {
  const TruthScene truth = ReadTruthScene(truth_dir);
  const MeshData mesh = ReadMesh(mesh_path);
  EvaluationReport report = Evaluate(truth, mesh, options);
  report.truth_name = truth_dir;
  report.mesh_name = mesh_path;
  return report;
}

const RegionScore* EvaluationReport::Region(int label) const {
  for (const RegionScore& r : regions)
    if (r.label == label) return &r;
  return nullptr;
}

const RegionScore* EvaluationReport::Region(const std::string& name) const {
  for (const RegionScore& r : regions)
    if (r.name == name) return &r;
  return nullptr;
}

std::string EvaluationReport::Table() const {
  std::ostringstream out;
  char line[512];
  const double g = ground_pixel_size;
  out << "\nFacets evaluation report\n";
  if (!truth_name.empty()) out << "  truth                 " << truth_name << "\n";
  if (!mesh_name.empty()) out << "  mesh                  " << mesh_name << "\n";
  std::snprintf(line, sizeof(line),
                "  GSD                   %.4f m\n"
                "  sample spacing        %.4f m (reconstruction), %.4f m (truth)\n"
                "  images                %zu\n"
                "  samples               %zu reconstruction, %zu truth (%zu seen)\n",
                g, sample_spacing, truth_sample_spacing, num_images,
                num_reconstruction_samples, num_truth_samples, num_truth_samples_seen);
  out << line;
  if (roi) {
    std::snprintf(line, sizeof(line), "  region of interest    [%.3f %.3f %.3f] - [%.3f %.3f %.3f]\n",
                  roi->min.x(), roi->min.y(), roi->min.z(), roi->max.x(), roi->max.y(),
                  roi->max.z());
    out << line;
  }

  out << "\nAccuracy (reconstruction -> truth)             metres                          "
         "                         GSD\n";
  std::snprintf(line, sizeof(line), "  %-18s %9s %9s %9s %9s %9s %9s   %7s %7s %7s %7s\n",
                "region", "samples", "mean", "median", "rms", "p90", "max", "median", "rms",
                "p90", "max");
  out << line;
  auto accuracy_row = [&](const std::string& name, const DistanceStats& s) {
    std::snprintf(line, sizeof(line),
                  "  %-18s %9zu %9.4f %9.4f %9.4f %9.4f %9.4f   %7.3f %7.3f %7.3f %7.3f\n",
                  name.c_str(), s.count, s.mean, s.median, s.rms, s.p90, s.max, s.median / g,
                  s.rms / g, s.p90 / g, s.max / g);
    out << line;
  };
  for (const RegionScore& r : regions) accuracy_row(r.name, r.accuracy);
  if (num_images > 0) {
    out << "  by the images seeing the closest truth point\n";
    for (const RegionScore& r : regions) {
      if (r.label == -1) continue;
      accuracy_row(r.name + " >=2 views", r.accuracy_multi_view);
      accuracy_row(r.name + " <2 views", r.accuracy_few_views);
    }
  }

  out << "\nSelf-intersections of the mesh: " << mesh_crossings.pairs << " crossing triangle pairs";
  if (mesh_crossings.unchecked > 0) out << " (" << mesh_crossings.unchecked << " triangles not checked)";
  out << "\n";
  out << "\nCompleteness (truth seen by the images -> reconstruction)\n";
  std::string head = "  region              samples";
  for (double t : thresholds_gsd) {
    char h[32];
    std::snprintf(h, sizeof(h), " %7s%-4g", "<=", t);
    head += h;
  }
  out << head << "  (GSD)\n";
  auto row = [&](const std::string& name, const CompletenessStats& c) {
    std::snprintf(line, sizeof(line), "  %-18s %9zu", name.c_str(), c.count);
    out << line;
    for (double w : c.within) {
      std::snprintf(line, sizeof(line), " %9.1f %%", 100.0 * w);
      out << line;
    }
    out << "\n";
  };
  for (const RegionScore& r : regions) row(r.name, r.completeness);
  if (heights.count > 0) {
    std::snprintf(line, sizeof(line),
                  "\nHeight errors (reconstruction - truth, highest points, %.2f m grid)\n"
                  "  points %zu (missing %zu)  rms %.4f  mean %.4f  min %.4f  max %.4f  m\n",
                  heights.spacing, heights.count, heights.missing, heights.rms, heights.mean,
                  heights.min, heights.max);
    out << line;
  }
  for (const WallLean& w : leaning_walls) {
    std::snprintf(line, sizeof(line),
                  "\nLeaning wall (building %d, wall %d): true lean %.2f deg (truth mesh fit %.2f), "
                  "reconstructed %.2f deg from %d vertices (plane rms %.3f m)\n",
                  w.building, w.wall, w.true_lean_deg, w.truth_fit_lean_deg, w.lean_deg, w.vertices, w.rms);
    out << line;
  }
  if (!sigma_by_views.empty()) {
    out << "\nReported sigma of the reconstruction's vertices by images seeing them (median / mean, m)\n";
    for (const SigmaByViews& r : sigma_by_views) {
      std::snprintf(line, sizeof(line),
                    "  %-10s <2 views: %6zu  %.4f / %.4f   2 views: %6zu  %.4f / %.4f   >=3 views: %6zu  %.4f / %.4f\n",
                    r.name.c_str(), r.count[0], r.median[0], r.mean[0], r.count[1], r.median[1], r.mean[1],
                    r.count[2], r.median[2], r.mean[2]);
      out << line;
    }
  }
  out << "  by view count\n";
  for (const RegionScore& r : regions) {
    if (r.label == -1) continue;
    row(r.name + " >=2 views", r.multi_view);
    row(r.name + " <2 views", r.few_views);
  }
  return out.str();
}

std::string EvaluationReport::Json(bool with_samples) const {
  nlohmann::json j;
  j["ground_pixel_size"] = ground_pixel_size;
  j["sample_spacing"] = sample_spacing;
  j["truth_sample_spacing"] = truth_sample_spacing;
  j["num_images"] = num_images;
  j["num_reconstruction_samples"] = num_reconstruction_samples;
  j["num_truth_samples"] = num_truth_samples;
  j["num_truth_samples_seen"] = num_truth_samples_seen;
  j["thresholds_gsd"] = thresholds_gsd;
  if (!truth_name.empty()) j["truth"] = truth_name;
  if (!mesh_name.empty()) j["mesh"] = mesh_name;
  j["mesh_crossing_pairs"] = mesh_crossings.pairs;
  j["mesh_unchecked_triangles"] = mesh_crossings.unchecked;
  if (roi) {
    j["region_of_interest"] = {{"min", {roi->min.x(), roi->min.y(), roi->min.z()}},
                               {"max", {roi->max.x(), roi->max.y(), roi->max.z()}}};
  }
  nlohmann::json regions_json = nlohmann::json::array();
  for (const RegionScore& r : regions) {
    regions_json.push_back({{"label", r.label},
                            {"name", r.name},
                            {"accuracy", StatsJson(r.accuracy, ground_pixel_size)},
                            {"accuracy_multi_view", StatsJson(r.accuracy_multi_view, ground_pixel_size)},
                            {"accuracy_few_views", StatsJson(r.accuracy_few_views, ground_pixel_size)},
                            {"completeness", CompletenessJson(r.completeness, thresholds_gsd)},
                            {"completeness_multi_view",
                             CompletenessJson(r.multi_view, thresholds_gsd)},
                            {"completeness_few_views",
                             CompletenessJson(r.few_views, thresholds_gsd)}});
  }
  j["regions"] = regions_json;
  j["height_errors"] = {{"count", heights.count}, {"missing", heights.missing},
                        {"rms", heights.rms},     {"mean", heights.mean},
                        {"min", heights.min},     {"max", heights.max},
                        {"spacing", heights.spacing}};
  for (const SigmaByViews& r : sigma_by_views) {
    nlohmann::json row = {{"label", r.label}, {"name", r.name}};
    const char* keys[3] = {"views_lt2", "views_2", "views_ge3"};
    for (int g = 0; g < 3; ++g) {
      row[keys[g]] = {{"count", r.count[g]}, {"median", r.median[g]}, {"mean", r.mean[g]}};
    }
    j["sigma_by_views"].push_back(row);
  }
  for (const WallLean& w : leaning_walls) {
    j["leaning_walls"].push_back(
        {{"building", w.building}, {"wall", w.wall}, {"true_lean_deg", w.true_lean_deg},
         {"truth_fit_lean_deg", w.truth_fit_lean_deg},
         {"lean_deg", std::isfinite(w.lean_deg) ? nlohmann::json(w.lean_deg) : nlohmann::json(nullptr)},
         {"vertices", w.vertices}, {"rms", w.rms}});
  }
  if (with_samples) {
    nlohmann::json s = nlohmann::json::array();
    for (const TruthSample& t : truth_samples) {
      s.push_back({t.point.x(), t.point.y(), t.point.z(), t.label, t.views, t.distance});
    }
    j["truth_samples"] = s;  // [x, y, z, label, views, distance]
  }
  return j.dump(2);
}

PlaneFit FitPlane(const std::vector<Eigen::Vector3d>& points) {
  if (points.size() < 3) throw std::invalid_argument("FitPlane: fewer than 3 points");
  PlaneFit fit;
  const PrincipalAxes principal = FitPrincipalAxes(points);
  fit.centroid = principal.centre;
  const Eigen::Vector3d ev = principal.eigenvalues;  // ascending
  if (!(ev(1) > 1e-12 * std::max(ev(2), 1e-300))) {
    throw std::invalid_argument("FitPlane: points are collinear or coincide");
  }
  fit.normal = principal.Normal().normalized();
  if (fit.normal.z() < 0) fit.normal = -fit.normal;
  double sum2 = 0;
  for (const auto& p : points) {
    const double r = (p - fit.centroid).dot(fit.normal);
    sum2 += r * r;
    fit.max_abs_residual = std::max(fit.max_abs_residual, std::abs(r));
  }
  fit.rms = std::sqrt(sum2 / static_cast<double>(points.size()));
  fit.tilt_from_vertical_deg = std::asin(std::min(1.0, std::abs(fit.normal.z()))) * 180.0 / M_PI;
  fit.slope_deg = 90.0 - fit.tilt_from_vertical_deg;
  return fit;
}

}  // namespace facets
