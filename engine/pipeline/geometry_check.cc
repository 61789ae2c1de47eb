#include "engine/pipeline/geometry_check.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <locale>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>

#include "engine/pipeline/region_choice.h"
#include "io/image_frame.h"
#include "io/image_io.h"

namespace facets {
namespace {

constexpr double kPi = 3.14159265358979323846;
// Region points: a grid of the region box (per axis X, Y, Z) and at most this many of
// the tie points inside it, evenly taken in their order.
constexpr int kGridXY = 7;
constexpr int kGridZ = 3;
constexpr size_t kMaxTiePointSamples = 400;

std::string Number(double value) {
  std::ostringstream out;
  out.imbue(std::locale::classic());
  out << value;
  return out.str();
}

std::string ImageLabel(const BlockImage& image) {
  return "image " + std::to_string(image.image_id) + " (" + image.name + ")";
}

std::string CameraLabel(const Camera& camera) {
  return "camera " + std::to_string(camera.camera_id) + " (" + CameraModelName(camera.model) + ")";
}

std::string Vector(const Eigen::Vector3d& v) {
  return "(" + Number(v.x()) + ", " + Number(v.y()) + ", " + Number(v.z()) + ")";
}

// The lower median (the smaller middle value of an even count); NaN when empty.
double LowerMedian(std::vector<double> values) {
  if (values.empty()) return std::numeric_limits<double>::quiet_NaN();
  const auto middle = values.begin() + (values.size() - 1) / 2;
  std::nth_element(values.begin(), middle, values.end());
  return *middle;
}

// The lens distortion over the image: along the ray from the principal point to each
// image corner the distorted radius must grow with the undistorted one (one to one),
// Undistort must invert Distort there to 0.01 px, and the corner's radius may change by
// a factor of 1/3..3 (strong wide-angle lenses stay near 0.6).
std::string LensProblem(const Camera& camera) {
  if (!camera.HasDistortion()) return "";
  const double focal = std::min(camera.FocalX(), camera.FocalY());
  for (const Eigen::Vector2d& corner : {Eigen::Vector2d(0, 0), Eigen::Vector2d(camera.width, 0),
                                       Eigen::Vector2d(0, camera.height),
                                       Eigen::Vector2d(camera.width, camera.height)}) {
    const Eigen::Vector2d distorted((corner.x() - camera.PrincipalX()) / camera.FocalX(),
                                    (corner.y() - camera.PrincipalY()) / camera.FocalY());
    if (distorted.norm() < 1e-9) continue;
    const Eigen::Vector2d undistorted = camera.Undistort(distorted);
    const std::string where = "image corner (" + Number(corner.x()) + ", " + Number(corner.y()) + ")";
    if (!undistorted.allFinite() || !((camera.Distort(undistorted) - distorted).norm() * focal <= 0.01)) {
      return "the lens distortion cannot be inverted at the " + where;
    }
    const double scale = distorted.norm() / undistorted.norm();
    if (!(scale >= 1.0 / 3.0 && scale <= 3.0)) {
      return "the lens distortion scales the radius of the " + where + " by " + Number(scale) +
             " (usable: 1/3 to 3)";
    }
    double last_radius = 0.0;
    for (int step = 1; step <= 16; ++step) {
      const double radius = camera.Distort(undistorted * (step / 16.0)).norm();
      if (!(radius > last_radius)) return "the lens distortion folds back between the image centre and the " + where;
      last_radius = radius;
    }
  }
  return "";
}

// Why the camera's numbers are unusable; empty when they are usable.
std::string CameraProblem(const Camera& camera) {
  const std::string who = CameraLabel(camera) + ": ";
  for (size_t i = 0; i < camera.params.size(); ++i) {
    if (!std::isfinite(camera.params[i])) return who + "parameter " + std::to_string(i) + " is not finite";
  }
  if (camera.width <= 0 || camera.height <= 0) return who + "the image size is not positive";
  const double size = std::max(camera.width, camera.height);
  for (const double focal : {camera.FocalX(), camera.FocalY()}) {
    if (!(focal >= 0.01 * size && focal <= 1e4 * size)) {
      return who + "focal length " + Number(focal) + " px is absurd for a " + std::to_string(camera.width) + " x " +
             std::to_string(camera.height) + " image (usable: 0.01 to 10000 times its larger side)";
    }
  }
  // Frames cut out of a larger one keep its principal point, which may lie well outside
  // them (a 230 px cut of a 11500 px aerial frame: 2300 px off); beyond 10 focal lengths
  // the rays of the image would lie beyond 84 degrees off the axis.
  const double off_limit = 10 * std::max({size, camera.FocalX(), camera.FocalY()});
  if (std::abs(camera.PrincipalX() - 0.5 * camera.width) > off_limit ||
      std::abs(camera.PrincipalY() - 0.5 * camera.height) > off_limit) {
    return who + "the principal point (" + Number(camera.PrincipalX()) + ", " + Number(camera.PrincipalY()) +
           ") px lies more than 10 focal lengths or image sizes off the image";
  }
  const std::string lens = LensProblem(camera);
  return lens.empty() ? "" : who + lens;
}

// Why the image's pose is unusable; empty when it is usable.
std::string PoseProblem(const BlockImage& image) {
  if (!image.cam_from_world.rotation.coeffs().allFinite()) return "its rotation is not finite";
  const Eigen::Vector3d& t = image.cam_from_world.translation;
  const Eigen::Vector3d centre = image.ProjectionCentre();
  auto usable = [](const Eigen::Vector3d& v) { return v.allFinite() && v.cwiseAbs().maxCoeff() <= kMaxCoordinate; };
  if (!usable(t)) return "its translation " + Vector(t) + " is not usable (finite, within 1e9 model units)";
  if (!usable(centre)) return "its projection centre " + Vector(centre) + " is not usable (within 1e9 model units)";
  return "";
}

std::vector<Eigen::Vector3d> RegionPoints(const ImageBlock& block, const RegionOfInterest& region) {
  std::vector<Eigen::Vector3d> points;
  const Eigen::Vector3d extent = region.max - region.min;
  for (int k = 0; k < kGridZ; ++k) {
    for (int j = 0; j < kGridXY; ++j) {
      for (int i = 0; i < kGridXY; ++i) {
        points.push_back(region.min + extent.cwiseProduct(Eigen::Vector3d(
                                          i / (kGridXY - 1.0), j / (kGridXY - 1.0), k / (kGridZ - 1.0))));
      }
    }
  }
  std::vector<Eigen::Vector3d> inside;
  for (const TiePoint& point : block.points) {
    if (region.Contains(point.xyz)) inside.push_back(point.xyz);
  }
  const size_t stride = std::max<size_t>(1, (inside.size() + kMaxTiePointSamples - 1) / kMaxTiePointSamples);
  for (size_t i = 0; i < inside.size(); i += stride) points.push_back(inside[i]);
  return points;
}

// Per image, the reprojection errors of its tie-point observations (px); +inf for a
// point behind the camera or a projection that is not a number.
std::vector<std::vector<double>> ReprojectionErrors(const ImageBlock& block) {
  std::map<int, size_t> index;
  for (size_t i = 0; i < block.images.size(); ++i) index[block.images[i].image_id] = i;
  std::vector<std::vector<double>> errors(block.images.size());
  for (const TiePoint& point : block.points) {
    for (const TrackElement& element : point.track) {
      const auto it = index.find(element.image_id);
      if (it == index.end()) continue;
      const BlockImage& image = block.images[it->second];
      if (element.point2d_idx < 0 || element.point2d_idx >= static_cast<int>(image.keypoints.size())) continue;
      const Eigen::Vector3d in_cam = image.cam_from_world * point.xyz;
      double error = std::numeric_limits<double>::infinity();
      if (in_cam.z() > 0) error = (block.CameraOf(image).ImageFromCam(in_cam) - image.keypoints[element.point2d_idx].xy).norm();
      errors[it->second].push_back(std::isfinite(error) ? error : std::numeric_limits<double>::infinity());
    }
  }
  return errors;
}

// Reprojection figures of the block and of each image; images beyond the bound get
// their problem.
void CheckReprojection(const ImageBlock& block, const GeometryCheckOptions& options, GeometryCheck* check) {
  const std::vector<std::vector<double>> errors = ReprojectionErrors(block);
  std::vector<double> all, image_medians;
  for (size_t i = 0; i < errors.size(); ++i) {
    ImageGeometry& image = check->images[i];
    image.observations = static_cast<int>(errors[i].size());
    if (errors[i].empty()) continue;
    std::vector<double> sorted = errors[i];
    std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
    image.median_reprojection_px = sorted[sorted.size() / 2];
    image_medians.push_back(image.median_reprojection_px);
    all.insert(all.end(), errors[i].begin(), errors[i].end());
    if (check->worst_image < 0 || image.median_reprojection_px > check->images[check->worst_image].median_reprojection_px) {
      check->worst_image = static_cast<int>(i);
    }
  }
  check->observations = static_cast<long long>(all.size());
  if (all.empty()) return;
  std::nth_element(all.begin(), all.begin() + all.size() / 2, all.end());
  check->median_reprojection_px = all[all.size() / 2];
  check->typical_image_median_px = LowerMedian(image_medians);
  check->relative_bound = options.max_image_median_ratio * check->typical_image_median_px > options.max_image_median_px;
  check->bad_image_median_px =
      std::max(options.max_image_median_px, options.max_image_median_ratio * check->typical_image_median_px);
  for (ImageGeometry& image : check->images) {
    if (image.observations == 0 || image.median_reprojection_px <= check->bad_image_median_px) continue;
    const std::string observations = std::to_string(image.observations) + " tie-point observations";
    if (std::isinf(image.median_reprojection_px)) {
      image.problems.push_back("most of its " + observations + " lie behind it or do not project");
    } else {
      image.problems.push_back("its " + observations + " reproject with a median of " +
                               Number(image.median_reprojection_px) + " px (bad above " +
                               Number(check->bad_image_median_px) + " px)");
    }
  }
}

// Per image, whether each region point projects into it, and the unit ray from its
// projection centre to the point.
struct RegionView {
  std::vector<char> sees;
  std::vector<Eigen::Vector3d> rays;
};

RegionView ViewOfRegion(const ImageBlock& block, const BlockImage& image, const std::vector<Eigen::Vector3d>& points,
                        int* in_front) {
  const ImageFrame frame(block.CameraOf(image));
  const Eigen::Vector3d centre = image.ProjectionCentre();
  RegionView view;
  view.sees.assign(points.size(), 0);
  view.rays.resize(points.size(), Eigen::Vector3d::Zero());
  *in_front = 0;
  for (size_t s = 0; s < points.size(); ++s) {
    if ((image.cam_from_world * points[s]).z() > 0) ++*in_front;
    if (!frame.Contains(image, points[s])) continue;
    view.sees[s] = 1;
    view.rays[s] = (points[s] - centre).normalized();
  }
  return view;
}

// Images still usable that see too few region points get their problem.
void CheckCoverage(const ImageBlock& block, const std::vector<Eigen::Vector3d>& points,
                   const GeometryCheckOptions& options, GeometryCheck* check, std::vector<RegionView>* views) {
  views->resize(block.images.size());
  const std::string of_region = " of the region's " + std::to_string(points.size()) + " points";
  for (size_t i = 0; i < block.images.size(); ++i) {
    ImageGeometry& image = check->images[i];
    if (!image.Usable()) continue;
    int in_front = 0;
    (*views)[i] = ViewOfRegion(block, block.images[i], points, &in_front);
    image.region_points_seen =
        static_cast<int>(std::count((*views)[i].sees.begin(), (*views)[i].sees.end(), char{1}));
    if (image.region_points_seen >= options.min_region_points) continue;
    if (in_front == 0) {
      image.problems.push_back("it sees none" + of_region + ": the region lies behind it");
    } else {
      image.problems.push_back("it sees " + std::to_string(image.region_points_seen) + of_region + " (needs " +
                               std::to_string(options.min_region_points) + "): the region lies outside its frame");
    }
  }
}

// Region points image i sees together with another usable image at a usable angle;
// seers[s] lists the images that see region point s.
int StereoPoints(const GeometryCheck& check, const std::vector<RegionView>& views,
                 const std::vector<std::vector<size_t>>& seers, size_t i, double cos_min) {
  int count = 0;
  const RegionView& own = views[i];
  for (size_t s = 0; s < own.sees.size(); ++s) {
    if (!own.sees[s]) continue;
    for (const size_t j : seers[s]) {
      if (j == i || !check.images[j].Usable()) continue;
      if (own.rays[s].dot(views[j].rays[s]) <= cos_min) {
        ++count;
        break;
      }
    }
  }
  return count;
}

// Images without a stereo partner get their problem, repeated until none loses its last
// partner to an image dropped.
void CheckStereo(const GeometryCheckOptions& options, const std::vector<RegionView>& views, GeometryCheck* check) {
  const double cos_min = std::cos(options.min_intersection_deg * kPi / 180.0);
  std::vector<std::vector<size_t>> seers;
  for (size_t i = 0; i < views.size(); ++i) {
    seers.resize(std::max(seers.size(), views[i].sees.size()));
    for (size_t s = 0; s < views[i].sees.size(); ++s) {
      if (views[i].sees[s]) seers[s].push_back(i);
    }
  }
  for (bool changed = true; changed;) {
    changed = false;
    for (size_t i = 0; i < views.size(); ++i) {
      ImageGeometry& image = check->images[i];
      if (!image.Usable()) continue;
      image.region_points_stereo = StereoPoints(*check, views, seers, i, cos_min);
      if (image.region_points_stereo >= options.min_region_points) continue;
      image.problems.push_back("no other usable image sees its region points with rays meeting at " +
                               Number(options.min_intersection_deg) + " deg or more (" +
                               std::to_string(image.region_points_stereo) + " of its " +
                               std::to_string(image.region_points_seen) + " region points have such a partner)");
      changed = true;
    }
  }
}

std::string Problems(const ImageGeometry& image) {
  std::string text;
  for (const std::string& problem : image.problems) text += (text.empty() ? "" : "; ") + problem;
  return text;
}

}  // namespace

int GeometryCheck::UsableCount() const {
  return static_cast<int>(std::count_if(images.begin(), images.end(), [](const ImageGeometry& i) { return i.Usable(); }));
}

std::vector<std::string> GeometryCheck::Lines() const {
  std::string summary = "geometry check: " + std::to_string(UsableCount()) + " of " + std::to_string(images.size()) +
                        " images usable (each sees the region with another at " + Number(min_intersection_deg) +
                        " deg or more; " + std::to_string(region_points) + " region points)";
  if (observations > 0) {
    const ImageGeometry& worst = images[worst_image];
    summary += "; tie points reproject with a median of " + Number(median_reprojection_px) + " px over " +
               std::to_string(observations) + " observations, worst image " + std::to_string(worst.image_id) +
               " (" + worst.name + ") " + Number(worst.median_reprojection_px) + " px";
  } else {
    summary += "; no tie-point observations to reproject";
  }
  std::vector<std::string> lines{summary};
  if (relative_bound) {
    lines.push_back("warning: the typical image's tie points reproject with a median of " +
                    Number(typical_image_median_px) + " px, images are dropped only above " +
                    Number(bad_image_median_px) + " px: the orientation may be poor");
  }
  for (const ImageGeometry& image : images) {
    if (!image.Usable()) {
      lines.push_back("warning: image " + std::to_string(image.image_id) + " (" + image.name +
                      ") dropped: " + Problems(image));
    }
  }
  return lines;
}

void CheckImageFilesUnique(const ImageBlock& block) {
  namespace fs = std::filesystem;
  std::map<std::string, const BlockImage*> files;
  for (const BlockImage& image : block.images) {
    std::string file = image.name;
    if (!image.path.empty()) {
      std::error_code error;
      const fs::path canonical = fs::weakly_canonical(image.path, error);
      file = error ? fs::path(image.path).lexically_normal().string() : canonical.string();
    }
    const auto [it, inserted] = files.emplace(file, &image);
    if (!inserted) {
      throw std::runtime_error(file + ": named by two images, " + ImageLabel(*it->second) + " and " +
                               ImageLabel(image) + "; each image file may appear once in a block");
    }
  }
}

GeometryCheck CheckBlockGeometry(const ImageBlock& block, const RegionOfInterest& region,
                                 const GeometryCheckOptions& options) {
  CheckImageFilesUnique(block);
  GeometryCheck check;
  check.min_intersection_deg = options.min_intersection_deg;
  check.images.resize(block.images.size());
  std::map<int, std::string> camera_problems;
  for (const auto& [id, camera] : block.cameras) camera_problems[id] = CameraProblem(camera);
  for (size_t i = 0; i < block.images.size(); ++i) {
    const BlockImage& image = block.images[i];
    ImageGeometry& geometry = check.images[i];
    geometry.image_id = image.image_id;
    geometry.name = image.name;
    if (const std::string& problem = camera_problems[image.camera_id]; !problem.empty()) {
      geometry.problems.push_back(problem);
    }
    if (const std::string problem = PoseProblem(image); !problem.empty()) geometry.problems.push_back(problem);
  }
  // Coverage first: it skips the images whose numbers are unusable, and only those.
  const std::vector<Eigen::Vector3d> points = RegionPoints(block, region);
  check.region_points = static_cast<int>(points.size());
  std::vector<RegionView> views;
  CheckCoverage(block, points, options, &check, &views);
  CheckReprojection(block, options, &check);
  CheckStereo(options, views, &check);
  return check;
}

ImageBlock KeepUsableImages(const ImageBlock& block, const GeometryCheck& check) {
  if (check.UsableCount() < 2) {
    std::string why;
    for (size_t i = 0; i < check.images.size(); ++i) {
      const ImageGeometry& image = check.images[i];
      if (!image.Usable()) why += "; " + ImageLabel(block.images[i]) + ": " + Problems(image);
    }
    throw std::runtime_error("geometry check: " + std::to_string(check.UsableCount()) + " of " +
                             std::to_string(check.images.size()) +
                             " images usable, a surface needs at least 2 that see the region with rays meeting at " +
                             Number(check.min_intersection_deg) + " deg or more" + why);
  }
  ImageBlock kept = block;
  kept.images.clear();
  kept.cameras.clear();
  std::set<int> kept_ids;
  for (size_t i = 0; i < block.images.size(); ++i) {
    if (!check.images[i].Usable()) continue;
    const BlockImage& image = block.images[i];
    kept.images.push_back(image);
    kept.cameras.emplace(image.camera_id, block.cameras.at(image.camera_id));
    kept_ids.insert(image.image_id);
  }
  for (TiePoint& point : kept.points) {
    std::erase_if(point.track, [&](const TrackElement& e) { return !kept_ids.count(e.image_id); });
  }
  return kept;
}

CheckedImageBlock CheckBlock(const ImageBlock& block, const std::optional<RegionOfInterest>& given,
                             const std::function<void(const std::string&)>& say) {
  CheckImageHeaders(block);
  CheckedImageBlock checked;
  checked.geometry = CheckBlockGeometry(block, ChooseRegion(block, given));
  for (const std::string& line : checked.geometry.Lines()) say(line);
  checked.block = KeepUsableImages(block, checked.geometry);
  return checked;
}

}  // namespace facets
