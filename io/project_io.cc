#include "io/project_io.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <numbers>
#include <set>
#include <stdexcept>

#include "io/atomic_file.h"
#include "io/input_file.h"

namespace facets {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// Errors name the file and the JSON path of the offending field, e.g.
// "block.json: images[3].omega is not a number".
class Reader {
 public:
  static constexpr unsigned long long kMaxLongLong = std::numeric_limits<long long>::max();

  explicit Reader(std::string file) : file_(std::move(file)) {}

  [[noreturn]] void Fail(const std::string& path, const std::string& message) const {
    throw std::runtime_error(file_ + ": " + path + " " + message);
  }

  static std::string Join(const std::string& path, const std::string& key) {
    return path.empty() ? key : path + "." + key;
  }
  static std::string Index(const std::string& path, size_t i) {
    return path + "[" + std::to_string(i) + "]";
  }

  const json& Field(const json& object, const std::string& path, const std::string& key) const {
    if (!object.is_object()) Fail(path.empty() ? "(top level)" : path, "is not an object");
    const auto it = object.find(key);
    if (it == object.end()) Fail(Join(path, key), "is missing");
    return *it;
  }
  // Every key of `object` must be one of `known`: a misspelt optional key would
  // otherwise be dropped without a word (docs/PROJECT_FILE.md lists the keys).
  void KnownKeys(const json& object, const std::string& path,
                 const std::vector<std::string>& known) const {
    if (!object.is_object()) Fail(path.empty() ? "(top level)" : path, "is not an object");
    for (const auto& item : object.items()) {
      if (std::find(known.begin(), known.end(), item.key()) == known.end()) {
        throw std::runtime_error(file_ + ": " + (path.empty() ? "top level" : path) + ": " +
                                 UnknownKeyMessage(item.key(), known));
      }
    }
  }
  const json* Optional(const json& object, const std::string& key) const {
    const auto it = object.find(key);
    return it == object.end() || it->is_null() ? nullptr : &*it;
  }

  double Number(const json& value, const std::string& path) const {
    if (!value.is_number()) Fail(path, "is not a number");
    const double v = value.get<double>();
    if (!std::isfinite(v)) Fail(path, "is not finite");
    return v;
  }
  long long Integer(const json& value, const std::string& path) const {
    if (!value.is_number_integer()) Fail(path, "is not an integer");
    if (value.is_number_unsigned() && value.get<unsigned long long>() > kMaxLongLong) {
      Fail(path, "is " + value.dump() + ", too large");
    }
    return value.get<long long>();
  }
  // An integer that is an id, index or size: within lo..INT_MAX, as the block stores them
  // in ints (a larger one would wrap: 4294967297 would become 1).
  int Int(const json& value, const std::string& path, long long lo = 0) const {
    const long long v = Integer(value, path);
    if (v < lo || v > std::numeric_limits<int>::max()) {
      Fail(path, "is " + std::to_string(v) + ", outside " + std::to_string(lo) + ".." +
                     std::to_string(std::numeric_limits<int>::max()));
    }
    return static_cast<int>(v);
  }
  std::string String(const json& value, const std::string& path) const {
    if (!value.is_string()) Fail(path, "is not a string");
    return value.get<std::string>();
  }
  const json& Array(const json& value, const std::string& path) const {
    if (!value.is_array()) Fail(path, "is not an array");
    return value;
  }
  Eigen::Vector3d Vector3(const json& value, const std::string& path) const {
    if (!value.is_array() || value.size() != 3) Fail(path, "is not an array of 3 numbers");
    return {Number(value[0], Index(path, 0)), Number(value[1], Index(path, 1)),
            Number(value[2], Index(path, 2))};
  }

  double NumberField(const json& object, const std::string& path, const std::string& key) const {
    return Number(Field(object, path, key), Join(path, key));
  }

 private:
  std::string file_;
};

Eigen::Matrix3d RotationX(double a) {
  return Eigen::AngleAxisd(a, Eigen::Vector3d::UnitX()).toRotationMatrix();
}
Eigen::Matrix3d RotationY(double a) {
  return Eigen::AngleAxisd(a, Eigen::Vector3d::UnitY()).toRotationMatrix();
}
Eigen::Matrix3d RotationZ(double a) {
  return Eigen::AngleAxisd(a, Eigen::Vector3d::UnitZ()).toRotationMatrix();
}

// Photo frame (x right, y up, z towards the viewer) -> COLMAP camera frame (x right,
// y down, z forward).
const Eigen::Matrix3d kPhotoToCam = Eigen::Vector3d(1, -1, -1).asDiagonal();

double RadiansPerUnit(const std::string& unit) {
  return unit == "gon" ? std::numbers::pi / 200.0 : std::numbers::pi / 180.0;
}

int NumFocalAndPrincipal(CameraModel model) {
  return model == CameraModel::kPinhole || model == CameraModel::kOpenCV ? 4 : 3;
}

Camera ReadCamera(const Reader& r, const json& node, const std::string& path) {
  r.KnownKeys(node, path,
              {"id", "model", "focal_length_mm", "pixel_size_um", "principal_point_offset_mm",
               "width_px", "height_px", "distortion"});
  const int id = r.Int(r.Field(node, path, "id"), Reader::Join(path, "id"));
  CameraModel model = CameraModel::kPinhole;
  if (const json* m = r.Optional(node, "model")) {
    const std::string name = r.String(*m, Reader::Join(path, "model"));
    try {
      model = CameraModelFromName(name);
    } catch (const std::invalid_argument& e) {
      r.Fail(Reader::Join(path, "model"), e.what());
    }
  }
  const double pixel_um = r.NumberField(node, path, "pixel_size_um");
  if (!(pixel_um > 0)) r.Fail(Reader::Join(path, "pixel_size_um"), "must be positive");
  const double px_per_mm = 1000.0 / pixel_um;

  const json& focal = r.Field(node, path, "focal_length_mm");
  const std::string focal_path = Reader::Join(path, "focal_length_mm");
  double fx_mm, fy_mm;
  if (focal.is_array()) {
    if (focal.size() != 2) r.Fail(focal_path, "must be a number or an array [cx_mm, cy_mm]");
    fx_mm = r.Number(focal[0], Reader::Index(focal_path, 0));
    fy_mm = r.Number(focal[1], Reader::Index(focal_path, 1));
    if (fx_mm != fy_mm && NumFocalAndPrincipal(model) == 3) {
      r.Fail(focal_path, "has two different values but model " + CameraModelName(model) +
                             " has a single focal length");
    }
  } else {
    fx_mm = fy_mm = r.Number(focal, focal_path);
  }
  if (!(fx_mm > 0) || !(fy_mm > 0)) r.Fail(focal_path, "must be positive");

  double x0_mm = 0, y0_mm = 0;
  if (const json* pp = r.Optional(node, "principal_point_offset_mm")) {
    const std::string pp_path = Reader::Join(path, "principal_point_offset_mm");
    if (!pp->is_array() || pp->size() != 2) r.Fail(pp_path, "is not an array [x0, y0]");
    x0_mm = r.Number((*pp)[0], Reader::Index(pp_path, 0));
    y0_mm = r.Number((*pp)[1], Reader::Index(pp_path, 1));
  }
  const int width = r.Int(r.Field(node, path, "width_px"), Reader::Join(path, "width_px"), 1);
  const int height = r.Int(r.Field(node, path, "height_px"), Reader::Join(path, "height_px"), 1);

  Camera camera = Camera::Create(model, fx_mm * px_per_mm, fy_mm * px_per_mm,
                                 0.5 * width + x0_mm * px_per_mm,
                                 0.5 * height - y0_mm * px_per_mm, width, height);
  camera.camera_id = id;
  camera.pixel_size_um = pixel_um;
  const size_t num_distortion = camera.params.size() - NumFocalAndPrincipal(model);
  const std::string dist_path = Reader::Join(path, "distortion");
  if (const json* d = r.Optional(node, "distortion")) {
    r.Array(*d, dist_path);
    if (d->size() != num_distortion) {
      r.Fail(dist_path, "has " + std::to_string(d->size()) + " coefficients, model " +
                            CameraModelName(model) + " needs " +
                            std::to_string(num_distortion));
    }
    for (size_t i = 0; i < num_distortion; ++i) {
      camera.params[NumFocalAndPrincipal(model) + i] =
          r.Number((*d)[i], Reader::Index(dist_path, i));
    }
  }
  try {
    camera.Check();
  } catch (const std::invalid_argument& e) {
    r.Fail(path, e.what());
  }
  return camera;
}

json Array3(const Eigen::Vector3d& v) { return json::array({v.x(), v.y(), v.z()}); }

// Checks format, version and rotation convention; returns radians per angle unit.
double ReadProjectConventions(const Reader& r, const json& root) {
  r.KnownKeys(root, "",
              {"format", "version", "angle_unit", "rotation", "crs", "origin",
               "mean_terrain_height", "region_of_interest", "cameras", "images", "tie_points"});
  if (r.String(r.Field(root, "", "format"), "format") != "facets-project") {
    r.Fail("format", "must be \"facets-project\"");
  }
  if (r.Integer(r.Field(root, "", "version"), "version") != 1) {
    r.Fail("version", "is not supported (this reader knows version 1)");
  }
  std::string unit = "deg";
  if (const json* u = r.Optional(root, "angle_unit")) unit = r.String(*u, "angle_unit");
  if (unit != "deg" && unit != "gon") r.Fail("angle_unit", "must be \"deg\" or \"gon\"");
  if (const json* rot = r.Optional(root, "rotation")) {
    if (r.String(*rot, "rotation") != "omega-phi-kappa") {
      r.Fail("rotation", "must be \"omega-phi-kappa\"");
    }
  }
  return RadiansPerUnit(unit);
}

// One image: id, path (relative to `dir`), camera and rotation from omega, phi, kappa
// (radians after `to_rad`); its global projection centre (m) goes to *centre, the
// translation is set once the origin is known.
BlockImage ReadImage(const Reader& r, const json& node, const std::string& ipath,
                     const fs::path& dir, double to_rad, const ImageBlock& block,
                     std::set<int>* image_ids, Eigen::Vector3d* centre) {
  r.KnownKeys(node, ipath,
              {"id", "path", "camera", "projection_centre", "omega", "phi", "kappa"});
  BlockImage image;
  image.image_id = r.Int(r.Field(node, ipath, "id"), Reader::Join(ipath, "id"));
  if (!image_ids->insert(image.image_id).second) {
    r.Fail(ipath + ".id", "duplicates image id " + std::to_string(image.image_id));
  }
  image.name = r.String(r.Field(node, ipath, "path"), Reader::Join(ipath, "path"));
  image.path = (dir / image.name).lexically_normal().string();
  image.camera_id = r.Int(r.Field(node, ipath, "camera"), Reader::Join(ipath, "camera"));
  if (!block.cameras.count(image.camera_id)) {
    r.Fail(ipath + ".camera", "refers to unknown camera " + std::to_string(image.camera_id));
  }
  *centre = r.Vector3(r.Field(node, ipath, "projection_centre"), ipath + ".projection_centre");
  const double omega = r.NumberField(node, ipath, "omega") * to_rad;
  const double phi = r.NumberField(node, ipath, "phi") * to_rad;
  const double kappa = r.NumberField(node, ipath, "kappa") * to_rad;
  const Eigen::Matrix3d object_from_photo = RotationX(omega) * RotationY(phi) * RotationZ(kappa);
  const Eigen::Matrix3d cam_from_world = kPhotoToCam * object_from_photo.transpose();
  image.cam_from_world.rotation = Eigen::Quaterniond(cam_from_world).normalized();
  return image;
}

// The given origin, else the mean projection centre horizontally rounded to whole
// kilometres (readable, and small enough that floats keep millimetres over a block) with
// Z = 0 so local heights stay heights; zero without images.
Eigen::Vector3d ReadOrigin(const Reader& r, const json& root,
                           const std::vector<Eigen::Vector3d>& centres) {
  if (const json* o = r.Optional(root, "origin")) return r.Vector3(*o, "origin");
  if (centres.empty()) return Eigen::Vector3d::Zero();
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& c : centres) mean += c;
  mean /= static_cast<double>(centres.size());
  return {std::round(mean.x() / 1000.0) * 1000.0, std::round(mean.y() / 1000.0) * 1000.0, 0.0};
}

// "track": [[image_id, point2d_idx], ...], every image id known.
std::vector<TrackElement> ReadTrack(const Reader& r, const json& track, const std::string& tpath,
                                    const std::set<int>& image_ids) {
  r.Array(track, tpath);
  std::vector<TrackElement> elements;
  for (size_t k = 0; k < track.size(); ++k) {
    const std::string epath = Reader::Index(tpath, k);
    const json& e = track[k];
    if (!e.is_array() || e.size() != 2) r.Fail(epath, "is not [image_id, point2d_idx]");
    TrackElement element;
    element.image_id = r.Int(e[0], epath + "[0]");
    element.point2d_idx = r.Int(e[1], epath + "[1]");
    if (!image_ids.count(element.image_id)) {
      r.Fail(epath + "[0]", "refers to unknown image " + std::to_string(element.image_id));
    }
    elements.push_back(element);
  }
  return elements;
}

// One tie point: global xyz (m) made local by subtracting `origin`.
TiePoint ReadTiePoint(const Reader& r, const json& node, const std::string& ppath,
                      const Eigen::Vector3d& origin, const std::set<int>& image_ids,
                      std::set<long long>* point_ids) {
  r.KnownKeys(node, ppath, {"id", "xyz", "rgb", "error", "track"});
  TiePoint point;
  point.point3d_id = r.Integer(r.Field(node, ppath, "id"), ppath + ".id");
  if (point.point3d_id < 0) r.Fail(ppath + ".id", "is negative");
  if (!point_ids->insert(point.point3d_id).second) {
    r.Fail(ppath + ".id", "duplicates tie point id " + std::to_string(point.point3d_id));
  }
  point.xyz = r.Vector3(r.Field(node, ppath, "xyz"), ppath + ".xyz") - origin;
  if (const json* rgb = r.Optional(node, "rgb")) {
    if (!rgb->is_array() || rgb->size() != 3) r.Fail(ppath + ".rgb", "is not [r, g, b]");
    for (int c = 0; c < 3; ++c) {
      point.rgb[c] = r.Int((*rgb)[c], Reader::Index(ppath + ".rgb", c));
    }
  }
  if (const json* e = r.Optional(node, "error")) point.error = r.Number(*e, ppath + ".error");
  if (const json* track = r.Optional(node, "track")) {
    point.track = ReadTrack(r, *track, ppath + ".track", image_ids);
  }
  return point;
}

// Region of interest and mean terrain height, both made local.
void ReadRegionAndHeight(const Reader& r, const json& root, ImageBlock* block) {
  if (const json* roi = r.Optional(root, "region_of_interest")) {
    r.KnownKeys(*roi, "region_of_interest", {"min", "max"});
    RegionOfInterest region;
    region.min = r.Vector3(r.Field(*roi, "region_of_interest", "min"), "region_of_interest.min") -
                 block->origin;
    region.max = r.Vector3(r.Field(*roi, "region_of_interest", "max"), "region_of_interest.max") -
                 block->origin;
    for (int axis = 0; axis < 3; ++axis) {
      if (region.min[axis] > region.max[axis]) {
        const std::string name(1, "XYZ"[axis]);
        r.Fail("region_of_interest", "has min " + name + " > max " + name + " (" +
                                         std::to_string(region.min[axis] + block->origin[axis]) +
                                         " > " +
                                         std::to_string(region.max[axis] + block->origin[axis]) +
                                         ")");
      }
    }
    block->roi = region;
  }
  if (const json* h = r.Optional(root, "mean_terrain_height")) {
    block->mean_height = r.Number(*h, "mean_terrain_height") - block->origin.z();
  }
}

json CameraJson(int id, const Camera& camera) {
  camera.Check();
  // Without a physical pixel size the file states pixel_size_um = 1: focal lengths
  // and offsets in mm are then pixels / 1000, and reading gives the same pixels.
  const double pixel_um = camera.pixel_size_um > 0 ? camera.pixel_size_um : 1.0;
  const double mm_per_px = pixel_um / 1000.0;
  json node;
  node["id"] = id;
  node["model"] = CameraModelName(camera.model);
  if (camera.FocalX() == camera.FocalY()) {
    node["focal_length_mm"] = camera.FocalX() * mm_per_px;
  } else {
    node["focal_length_mm"] = {camera.FocalX() * mm_per_px, camera.FocalY() * mm_per_px};
  }
  node["pixel_size_um"] = pixel_um;
  node["principal_point_offset_mm"] = {(camera.PrincipalX() - 0.5 * camera.width) * mm_per_px,
                                       (0.5 * camera.height - camera.PrincipalY()) * mm_per_px};
  node["width_px"] = camera.width;
  node["height_px"] = camera.height;
  const int first = NumFocalAndPrincipal(camera.model);
  if (static_cast<int>(camera.params.size()) > first) {
    node["distortion"] = std::vector<double>(camera.params.begin() + first, camera.params.end());
  }
  return node;
}

// An image with its path relative to `dir`, its global projection centre and omega,
// phi, kappa in degrees.
json ImageJson(const BlockImage& image, const Eigen::Vector3d& origin, const fs::path& dir) {
  constexpr double kDegrees = 180.0 / std::numbers::pi;
  const Eigen::Matrix3d object_from_photo =
      image.cam_from_world.rotation.toRotationMatrix().transpose() * kPhotoToCam;
  const Eigen::Matrix3d& R = object_from_photo;
  // R = R_x(omega) R_y(phi) R_z(kappa): r13 = sin(phi), r23 = -sin(omega) cos(phi),
  // r33 = cos(omega) cos(phi), r12 = -cos(phi) sin(kappa), r11 = cos(phi) cos(kappa).
  const double phi = std::atan2(R(0, 2), std::hypot(R(0, 0), R(0, 1)));
  const double omega = std::atan2(-R(1, 2), R(2, 2));
  const double kappa = std::atan2(-R(0, 1), R(0, 0));
  std::string file = image.name;
  if (!image.path.empty()) {
    file = fs::absolute(fs::path(image.path)).lexically_normal().lexically_relative(dir)
               .generic_string();
    if (file.empty()) file = image.path;
  }
  json node;
  node["id"] = image.image_id;
  node["path"] = file;
  node["camera"] = image.camera_id;
  node["projection_centre"] = Array3(image.ProjectionCentre() + origin);
  node["omega"] = omega * kDegrees + 0.0;  // no "-0.0"
  node["phi"] = phi * kDegrees + 0.0;  // no "-0.0"
  node["kappa"] = kappa * kDegrees + 0.0;  // no "-0.0"
  return node;
}

json TiePointsJson(const std::vector<TiePoint>& tie_points, const Eigen::Vector3d& origin) {
  json points = json::array();
  for (const TiePoint& point : tie_points) {
    json track = json::array();
    for (const TrackElement& e : point.track) track.push_back({e.image_id, e.point2d_idx});
    points.push_back({{"id", point.point3d_id},
                      {"xyz", Array3(point.xyz + origin)},
                      {"rgb", {point.rgb.x(), point.rgb.y(), point.rgb.z()}},
                      {"error", point.error},
                      {"track", track}});
  }
  return points;
}

}  // namespace

ImageBlock ReadProject(const std::string& path) {
  std::ifstream in = OpenInputFile(path, "project file");
  json root;
  try {
    root = json::parse(in);
  } catch (const json::exception& e) {
    throw std::runtime_error(path + ": not valid JSON: " + e.what());
  }
  const Reader r(path);
  const double to_rad = ReadProjectConventions(r, root);

  ImageBlock block;
  if (const json* crs = r.Optional(root, "crs")) block.crs = r.String(*crs, "crs");

  const json& cameras = r.Array(r.Field(root, "", "cameras"), "cameras");
  for (size_t i = 0; i < cameras.size(); ++i) {
    const std::string cpath = Reader::Index("cameras", i);
    Camera camera = ReadCamera(r, cameras[i], cpath);
    if (!block.cameras.emplace(camera.camera_id, camera).second) {
      r.Fail(cpath + ".id", "duplicates camera id " + std::to_string(camera.camera_id));
    }
  }

  // Global projection centres first: the origin may be derived from them.
  const json& images = r.Array(r.Field(root, "", "images"), "images");
  std::vector<Eigen::Vector3d> centres(images.size());
  std::set<int> image_ids;
  const fs::path dir = fs::path(path).parent_path();
  for (size_t i = 0; i < images.size(); ++i) {
    block.images.push_back(ReadImage(r, images[i], Reader::Index("images", i), dir, to_rad,
                                     block, &image_ids, &centres[i]));
  }
  block.origin = ReadOrigin(r, root, centres);
  for (size_t i = 0; i < block.images.size(); ++i) {
    Rigid3d& pose = block.images[i].cam_from_world;
    pose.translation = -(pose.rotation * (centres[i] - block.origin));
  }
  ReadRegionAndHeight(r, root, &block);

  if (const json* points = r.Optional(root, "tie_points")) {
    r.Array(*points, "tie_points");
    std::set<long long> point_ids;
    for (size_t i = 0; i < points->size(); ++i) {
      block.points.push_back(ReadTiePoint(r, (*points)[i], Reader::Index("tie_points", i),
                                          block.origin, image_ids, &point_ids));
    }
  }
  return block;
}

void WriteProject(const ImageBlock& block, const std::string& path) {
  json root;
  root["format"] = "facets-project";
  root["version"] = 1;
  root["angle_unit"] = "deg";
  root["rotation"] = "omega-phi-kappa";
  if (!block.crs.empty()) root["crs"] = block.crs;
  root["origin"] = Array3(block.origin);
  if (block.mean_height) root["mean_terrain_height"] = *block.mean_height + block.origin.z();
  if (block.roi) {
    root["region_of_interest"] = {{"min", Array3(block.roi->min + block.origin)},
                                  {"max", Array3(block.roi->max + block.origin)}};
  }
  json cameras = json::array();
  for (const auto& [id, camera] : block.cameras) cameras.push_back(CameraJson(id, camera));
  root["cameras"] = cameras;

  const fs::path dir = fs::absolute(fs::path(path)).lexically_normal().parent_path();
  json images = json::array();
  for (const BlockImage& image : block.images) images.push_back(ImageJson(image, block.origin, dir));
  root["images"] = images;
  if (!block.points.empty()) root["tie_points"] = TiePointsJson(block.points, block.origin);
  WriteFileAtomically(path, root.dump(2) + "\n");
}

}  // namespace facets
