#include "scenes/scene.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <stdexcept>

#include "io/input_file.h"

namespace facets {
namespace {

constexpr double kDeg = M_PI / 180.0;

// The keys the parser looked for in each object it read (every read of a key, optional
// ones too, asks Field::Has first). Any other key of those objects is unknown: a misspelt
// optional key would otherwise be dropped without a word.
class AskedKeys {
 public:
  void Ask(const nlohmann::json& object, const std::string& path, const std::string& key) {
    auto it = std::find_if(objects_.begin(), objects_.end(), [&](const Object& o) { return o.json == &object; });
    if (it == objects_.end()) it = objects_.insert(objects_.end(), Object{&object, path, {}});
    if (std::find(it->keys.begin(), it->keys.end(), key) == it->keys.end()) it->keys.push_back(key);
  }
  // Throws std::invalid_argument naming the file, the object, the key and the nearest known one.
  void RefuseOthers(const std::string& source) const {
    for (const Object& object : objects_) {
      for (const auto& item : object.json->items()) {
        if (std::find(object.keys.begin(), object.keys.end(), item.key()) != object.keys.end()) continue;
        throw std::invalid_argument(source + ": " + (object.path.empty() ? "top level" : object.path) + ": " +
                                    UnknownKeyMessage(item.key(), object.keys));
      }
    }
  }

 private:
  struct Object {
    const nlohmann::json* json;
    std::string path;
    std::vector<std::string> keys;
  };
  std::vector<Object> objects_;  // in the order first read
};

// Reads fields of one JSON object and names the file and JSON pointer on error.
class Field {
 public:
  Field(const nlohmann::json& j, std::string source, std::string path, AskedKeys* asked)
      : j_(j), source_(std::move(source)), path_(std::move(path)), asked_(asked) {}

  [[noreturn]] void Fail(const std::string& key, const std::string& what) const {
    throw std::invalid_argument(source_ + ": " + path_ + "/" + key + ": " + what);
  }
  bool Has(const std::string& key) const {
    if (!j_.is_object()) return false;
    asked_->Ask(j_, path_, key);
    return j_.contains(key);
  }
  Field Child(const std::string& key) const {
    if (!Has(key)) Fail(key, "missing");
    return Field(j_.at(key), source_, path_ + "/" + key, asked_);
  }
  const nlohmann::json& json() const { return j_; }
  const std::string& path() const { return path_; }
  const std::string& source() const { return source_; }

  double Number(const std::string& key, std::optional<double> fallback = std::nullopt) const {
    if (!Has(key)) {
      if (fallback) return *fallback;
      Fail(key, "missing (expected a number)");
    }
    const auto& v = j_.at(key);
    if (!v.is_number()) Fail(key, "expected a number");
    const double x = v.get<double>();
    if (!std::isfinite(x)) Fail(key, "not finite");
    return x;
  }
  int Int(const std::string& key, std::optional<int> fallback = std::nullopt) const {
    if (!Has(key)) {
      if (fallback) return *fallback;
      Fail(key, "missing (expected an integer)");
    }
    const auto& v = j_.at(key);
    if (!v.is_number_integer()) Fail(key, "expected an integer");
    return v.get<int>();
  }
  bool Bool(const std::string& key, bool fallback) const {
    if (!Has(key)) return fallback;
    if (!j_.at(key).is_boolean()) Fail(key, "expected true or false");
    return j_.at(key).get<bool>();
  }
  std::string String(const std::string& key,
                     std::optional<std::string> fallback = std::nullopt) const {
    if (!Has(key)) {
      if (fallback) return *fallback;
      Fail(key, "missing (expected a string)");
    }
    if (!j_.at(key).is_string()) Fail(key, "expected a string");
    return j_.at(key).get<std::string>();
  }
  template <int N>
  Eigen::Matrix<double, N, 1> Vec(const std::string& key,
                                  std::optional<Eigen::Matrix<double, N, 1>> fallback =
                                      std::nullopt) const {
    if (!Has(key)) {
      if (fallback) return *fallback;
      Fail(key, "missing (expected an array of " + std::to_string(N) + " numbers)");
    }
    const auto& v = j_.at(key);
    if (!v.is_array() || v.size() != static_cast<size_t>(N)) {
      Fail(key, "expected an array of " + std::to_string(N) + " numbers");
    }
    Eigen::Matrix<double, N, 1> out;
    for (int i = 0; i < N; ++i) {
      if (!v[i].is_number() || !std::isfinite(v[i].get<double>())) {
        Fail(key + "/" + std::to_string(i), "expected a finite number");
      }
      out[i] = v[i].get<double>();
    }
    return out;
  }
  // Array field; empty when absent.
  std::vector<Field> Array(const std::string& key, bool required = false) const {
    std::vector<Field> out;
    if (!Has(key)) {
      if (required) Fail(key, "missing (expected an array)");
      return out;
    }
    const auto& v = j_.at(key);
    if (!v.is_array()) Fail(key, "expected an array");
    for (size_t i = 0; i < v.size(); ++i) {
      if (!v[i].is_object() && !v[i].is_array()) {
        Fail(key + "/" + std::to_string(i), "expected an object");
      }
      out.emplace_back(v[i], source_, path_ + "/" + key + "/" + std::to_string(i), asked_);
    }
    return out;
  }

 private:
  const nlohmann::json& j_;
  std::string source_;
  std::string path_;
  AskedKeys* asked_;
};

void Require(bool ok, const Field& f, const std::string& key, const std::string& what) {
  if (!ok) f.Fail(key, what);
}

// "type" of a shape, with the region label that type has by default.
void ParseShapeType(const Field& f, Shape* s) {
  const std::string type = f.String("type");
  if (type == "terrain") {
    s->type = ShapeType::kTerrain;
  } else if (type == "plane") {
    s->type = ShapeType::kPlane;
  } else if (type == "gable_roof") {
    s->type = ShapeType::kGableRoof;
    s->label = kLabelRoof;
  } else if (type == "parabolic_cylinder") {
    s->type = ShapeType::kParabolicCylinder;
    s->label = kLabelRoof;
  } else if (type == "building") {
    s->type = ShapeType::kBuilding;
    s->label = kLabelRoof;
  } else if (type == "blob") {
    s->type = ShapeType::kBlob;
    s->label = kLabelObject;
  } else if (type == "mesh") {
    s->type = ShapeType::kMesh;
    s->label = kLabelObject;
  } else {
    f.Fail("type", "unknown shape type '" + type +
                       "' (terrain, plane, gable_roof, parabolic_cylinder, building, blob, "
                       "mesh)");
  }
}

// "waves": [[amplitude, wavelength, direction_deg, phase_deg], ...] (m, m, deg, deg).
std::vector<Eigen::Vector4d> ParseWaves(const Field& f) {
  std::vector<Eigen::Vector4d> waves;
  for (const Field& w : f.Array("waves")) {
    const auto& v = w.json();
    if (!v.is_array() || v.size() != 4) {
      throw std::invalid_argument(f.source() + ": " + w.path() +
                                  ": expected [amplitude, wavelength, direction_deg, "
                                  "phase_deg]");
    }
    Eigen::Vector4d wave;
    for (int i = 0; i < 4; ++i) {
      if (!v[i].is_number()) {
        throw std::invalid_argument(f.source() + ": " + w.path() + "/" + std::to_string(i) +
                                    ": expected a number");
      }
      wave[i] = v[i].get<double>();
    }
    if (wave[1] <= 0) {
      throw std::invalid_argument(f.source() + ": " + w.path() + "/1: wavelength must be > 0");
    }
    waves.push_back(wave);
  }
  return waves;
}

RoofType ParseRoofType(const Field& f) {
  const std::string roof = f.String("roof", "flat");
  if (roof == "flat") return RoofType::kFlat;
  if (roof == "gable") return RoofType::kGable;
  if (roof == "hip") return RoofType::kHip;
  f.Fail("roof", "unknown roof type '" + roof + "' (flat, gable, hip)");
}

Shape ParseShape(const Field& f, const std::string& base_dir) {
  Shape s;
  ParseShapeType(f, &s);
  s.label = f.Int("label", s.label);
  Require(s.label >= 0 && s.label <= 3, f, "label", "must be 0..3");
  s.centre = f.Vec<3>("centre", Eigen::Vector3d::Zero());
  s.azimuth_deg = f.Number("azimuth_deg", 0.0);
  s.length = f.Number("length", s.length);
  s.width = f.Number("width", s.width);
  Require(s.length > 0, f, "length", "must be > 0");
  Require(s.width > 0, f, "width", "must be > 0");
  s.slope_deg = f.Number("slope_deg", s.slope_deg);
  Require(s.slope_deg >= 0 && s.slope_deg < 80, f, "slope_deg", "must be in [0, 80)");
  s.height = f.Number("height", s.height);
  s.step = f.Number("step", 0.0);
  Require(s.step >= 0, f, "step", "must be >= 0");
  s.waves = ParseWaves(f);
  s.roof = ParseRoofType(f);
  s.wall_lean_deg = f.Vec<4>("wall_lean_deg", Eigen::Vector4d::Zero());
  for (int i = 0; i < 4; ++i) {
    Require(std::abs(s.wall_lean_deg[i]) < 45, f, "wall_lean_deg/" + std::to_string(i),
            "must be within +-45 degrees");
  }
  s.radius = f.Number("radius", s.radius);
  Require(s.radius > 0, f, "radius", "must be > 0");
  s.lobes_seed = f.Int("lobes_seed", s.lobes_seed);
  s.lobe_amplitude = f.Number("lobe_amplitude", s.lobe_amplitude);
  Require(s.lobe_amplitude >= 0 && s.lobe_amplitude < 0.9, f, "lobe_amplitude",
          "must be in [0, 0.9)");
  if (s.type == ShapeType::kMesh) {
    const std::string file = f.String("file");
    std::filesystem::path p(file);
    if (p.is_relative() && !base_dir.empty()) p = std::filesystem::path(base_dir) / p;
    s.mesh_path = p.string();
  }
  if (s.type == ShapeType::kBuilding) {
    Require(s.height > 0, f, "height", "eave height must be > 0");
  }
  return s;
}

LayoutType ParseLayoutType(const Field& f) {
  const std::string type = f.String("type");
  if (type == "stereo") return LayoutType::kStereo;
  if (type == "block") return LayoutType::kBlock;
  if (type == "ring") return LayoutType::kRing;
  if (type == "list") return LayoutType::kList;
  f.Fail("type", "unknown camera layout '" + type + "' (stereo, block, ring, list)");
}

// The camera (focal length, pixel size, frame) and the flight: heights (m), overlaps,
// rows and columns of the block, obliques.
void ParseCameraAndFlight(const Field& f, CameraLayout* c) {
  c->focal_mm = f.Number("focal_mm", c->focal_mm);
  c->pixel_um = f.Number("pixel_um", c->pixel_um);
  Require(c->focal_mm > 0, f, "focal_mm", "must be > 0");
  Require(c->pixel_um > 0, f, "pixel_um", "must be > 0");
  c->width = f.Int("width", 0);
  c->height = f.Int("height", 0);
  Require(c->width >= 0, f, "width", "must be >= 0");
  Require(c->height >= 0, f, "height", "must be >= 0");
  c->frame_mm = f.Number("frame_mm", c->frame_mm);
  Require(c->frame_mm > 0, f, "frame_mm", "must be > 0");
  c->flying_height = f.Number("flying_height", c->flying_height);
  Require(c->flying_height > 0, f, "flying_height", "must be > 0");
  c->reference_height = f.Number("reference_height", 0.0);
  c->overlap = f.Number("overlap", c->overlap);
  Require(c->overlap >= 0 && c->overlap < 1, f, "overlap", "must be in [0, 1)");
  c->forward_overlap = f.Number("forward_overlap", c->forward_overlap);
  c->side_overlap = f.Number("side_overlap", c->side_overlap);
  Require(c->forward_overlap >= 0 && c->forward_overlap < 1, f, "forward_overlap",
          "must be in [0, 1)");
  Require(c->side_overlap >= 0 && c->side_overlap < 1, f, "side_overlap", "must be in [0, 1)");
  c->rows = f.Int("rows", c->rows);
  c->cols = f.Int("cols", c->cols);
  Require(c->rows >= 1, f, "rows", "must be >= 1");
  Require(c->cols >= 1, f, "cols", "must be >= 1");
  c->obliques = f.Int("obliques", c->obliques);
  Require(c->obliques >= 0 && c->obliques <= 4, f, "obliques", "must be 0..4");
  c->oblique_tilt_deg = f.Number("oblique_tilt_deg", c->oblique_tilt_deg);
  Require(c->oblique_tilt_deg > 0 && c->oblique_tilt_deg < 80, f, "oblique_tilt_deg",
          "must be in (0, 80)");
  c->oblique_strip = f.Int("oblique_strip", c->oblique_strip);
  Require(c->oblique_strip >= 1 && c->oblique_strip <= 9, f, "oblique_strip", "must be 1..9");
  c->oblique_base = f.Number("oblique_base", c->oblique_base);
  Require(c->oblique_base >= 0, f, "oblique_base", "must be >= 0");
  const std::string axes = f.String("oblique_axes", "parallel");
  Require(axes == "parallel" || axes == "convergent", f, "oblique_axes",
          "expected 'parallel' or 'convergent'");
  c->oblique_convergent = axes == "convergent";
}

// "rings" (ring layout) and "cameras" (list layout).
void ParseRingsAndCameras(const Field& f, CameraLayout* c) {
  for (const Field& r : f.Array("rings")) {
    RingSpec ring;
    ring.radius = r.Number("radius");
    ring.elevation_deg = r.Number("elevation_deg");
    ring.count = r.Int("count");
    ring.azimuth_offset_deg = r.Number("azimuth_offset_deg", 0.0);
    Require(ring.radius > 0, r, "radius", "must be > 0");
    Require(ring.count >= 1, r, "count", "must be >= 1");
    Require(std::abs(ring.elevation_deg) < 89, r, "elevation_deg", "must be within +-89");
    c->rings.push_back(ring);
  }
  for (const Field& e : f.Array("cameras")) {
    ExplicitCamera cam;
    cam.centre = e.Vec<3>("centre");
    cam.target = e.Vec<3>("target");
    cam.up = e.Vec<3>("up", Eigen::Vector3d::UnitY());
    Require((cam.target - cam.centre).norm() > 0, e, "target", "equals the centre");
    c->cameras.push_back(cam);
  }
}

CameraLayout ParseLayout(const Field& f) {
  CameraLayout c;
  c.type = ParseLayoutType(f);
  ParseCameraAndFlight(f, &c);
  c.target = f.Vec<3>("target", Eigen::Vector3d::Zero());
  ParseRingsAndCameras(f, &c);
  c.crop_to_roi = f.Bool("crop_to_roi", c.type == LayoutType::kStereo);
  c.crop_margin_px = f.Int("crop_margin_px", c.crop_margin_px);
  Require(c.crop_margin_px >= 0, f, "crop_margin_px", "must be >= 0");
  if (c.type == LayoutType::kRing) {
    Require(!c.rings.empty(), f, "rings", "a ring layout needs at least one ring");
  }
  if (c.type == LayoutType::kList) {
    Require(!c.cameras.empty(), f, "cameras", "a list layout needs at least one camera");
  }
  if (c.type != LayoutType::kStereo || !c.crop_to_roi) {
    Require(c.width > 0, f, "width", "must be > 0 for this layout");
    Require(c.height > 0, f, "height", "must be > 0 for this layout");
  }
  return c;
}

AlbedoBand ParseAlbedoBand(const Field& b) {
  AlbedoBand band;
  band.wavelength_min = b.Number("wavelength_min");
  band.wavelength_max = b.Number("wavelength_max");
  band.contrast = b.Number("contrast", band.contrast);
  band.components = b.Int("components", band.components);
  Require(band.wavelength_min > 0, b, "wavelength_min", "must be > 0");
  Require(band.wavelength_max >= band.wavelength_min, b, "wavelength_max",
          "must be >= wavelength_min");
  Require(band.contrast >= 0, b, "contrast", "must be >= 0");
  Require(band.components >= 1 && band.components <= 1000, b, "components", "must be 1..1000");
  return band;
}

AlbedoPatch ParseAlbedoPatch(const Field& p) {
  AlbedoPatch patch;
  patch.box = p.String("kind", "rectangle") == "box";
  if (!patch.box && p.String("kind", "rectangle") != "rectangle") {
    p.Fail("kind", "expected 'rectangle' or 'box'");
  }
  patch.centre = p.Vec<3>("centre");
  if (patch.box) {
    patch.size = p.Vec<3>("size");
  } else {
    const Eigen::Vector2d size = p.Vec<2>("size");
    patch.size = Eigen::Vector3d(size.x(), size.y(), 0);
  }
  Require((patch.size.head<2>().array() > 0).all(), p, "size", "must be > 0");
  patch.azimuth_deg = p.Number("azimuth_deg", 0.0);
  patch.albedo = p.Number("albedo", 0.5);
  Require(patch.albedo >= 0 && patch.albedo <= 1, p, "albedo", "must be in [0, 1]");
  return patch;
}

// "albedo": the procedural texture (wavelengths in m; 0 = chosen from the GSD later).
void ParseAlbedo(const Field& a, AlbedoOptions* o) {
  o->seed = a.Int("seed", o->seed);
  o->components = a.Int("components", o->components);
  Require(o->components >= 1 && o->components <= 1000, a, "components", "must be 1..1000");
  o->wavelength_min = a.Number("wavelength_min", 0.0);
  o->wavelength_max = a.Number("wavelength_max", 0.0);
  Require(o->wavelength_min >= 0, a, "wavelength_min", "must be >= 0");
  Require(o->wavelength_max >= o->wavelength_min, a, "wavelength_max",
          "must be >= wavelength_min");
  o->mean = a.Number("mean", o->mean);
  o->contrast = a.Number("contrast", o->contrast);
  Require(o->mean >= 0 && o->mean <= 1, a, "mean", "must be in [0, 1]");
  Require(o->contrast >= 0, a, "contrast", "must be >= 0");
  for (const Field& b : a.Array("extra_bands")) o->extra_bands.push_back(ParseAlbedoBand(b));
  for (const Field& p : a.Array("patches")) o->patches.push_back(ParseAlbedoPatch(p));
}

// "sun": azimuth and elevation (deg) and the ambient share of the light (0..1).
void ParseSun(const Field& s, SunOptions* sun) {
  sun->azimuth_deg = s.Number("azimuth_deg", sun->azimuth_deg);
  sun->elevation_deg = s.Number("elevation_deg", sun->elevation_deg);
  sun->ambient = s.Number("ambient", sun->ambient);
  sun->cast_shadows = s.Bool("cast_shadows", sun->cast_shadows);
  Require(sun->ambient >= 0 && sun->ambient <= 1, s, "ambient", "must be in [0, 1]");
  Require(sun->elevation_deg > 0 && sun->elevation_deg <= 90, s, "elevation_deg",
          "must be in (0, 90]");
}

// Image noise, supersampling, seed, mesh tolerance and tie points of the rendering.
void ParseRendering(const Field& f, Scene* scene) {
  scene->noise_sigma = f.Number("noise_sigma", scene->noise_sigma);
  Require(scene->noise_sigma >= 0, f, "noise_sigma", "must be >= 0");
  scene->supersampling = f.Int("supersampling", scene->supersampling);
  Require(scene->supersampling >= 1 && scene->supersampling <= 16, f, "supersampling",
          "must be 1..16");
  scene->seed = f.Int("seed", scene->seed);
  scene->sagitta_tolerance = f.Number("sagitta_tolerance", scene->sagitta_tolerance);
  Require(scene->sagitta_tolerance > 0, f, "sagitta_tolerance", "must be > 0");
  scene->tie_points = f.Int("tie_points", scene->tie_points);
  Require(scene->tie_points >= 0, f, "tie_points", "must be >= 0");
  scene->tie_point_sigma = f.Number("tie_point_sigma", 0.0);
  if (scene->tie_point_sigma == 0) scene->tie_point_sigma = 0.25 * scene->ground_pixel_size;
}

}  // namespace

std::string RegionLabelName(int label) {
  switch (label) {
    case kLabelGround: return "ground";
    case kLabelRoof: return "roof";
    case kLabelWall: return "wall";
    case kLabelObject: return "object";
    default: return "unknown";
  }
}

bool AlbedoPatch::Contains(const Eigen::Vector3d& p) const {
  const double a = azimuth_deg * kDeg;
  const Eigen::Vector3d d = p - centre;
  const double u = std::cos(a) * d.x() + std::sin(a) * d.y();
  const double v = -std::sin(a) * d.x() + std::cos(a) * d.y();
  if (std::abs(u) > 0.5 * size.x() || std::abs(v) > 0.5 * size.y()) return false;
  return !box || std::abs(d.z()) <= 0.5 * size.z();
}

Eigen::Vector3d SunOptions::Direction() const {
  const double az = azimuth_deg * kDeg, el = elevation_deg * kDeg;
  return Eigen::Vector3d(std::sin(az) * std::cos(el), std::cos(az) * std::cos(el),
                         std::sin(el));
}

void Scene::Check() const {
  auto fail = [&](const std::string& what) {
    throw std::invalid_argument((source_path.empty() ? name : source_path) + ": " + what);
  };
  if (!(ground_pixel_size > 0)) fail("/ground_pixel_size must be > 0");
  if (!(noise_sigma >= 0)) fail("/noise_sigma must be >= 0");
  if (supersampling < 1 || supersampling > 16) fail("/supersampling must be 1..16");
  if (surface.empty()) fail("/surface is empty");
  if (!(roi.max.array() > roi.min.array()).all()) fail("/region_of_interest: max <= min");
  if (sun.ambient < 0 || sun.ambient > 1) fail("/sun/ambient must be in [0, 1]");
  if (!(sagitta_tolerance > 0)) fail("/sagitta_tolerance must be > 0");
}

Scene ParseScene(const nlohmann::json& json, const std::string& source_name) {
  if (!json.is_object()) {
    throw std::invalid_argument(source_name + ": top level must be a JSON object");
  }
  AskedKeys asked;
  const Field f(json, source_name, "", &asked);
  Scene scene;
  scene.json = json;
  scene.name = f.String("name");
  f.String("description", "");  // for the reader of the file
  scene.ground_pixel_size = f.Number("ground_pixel_size");
  Require(scene.ground_pixel_size > 0, f, "ground_pixel_size", "must be > 0");
  const Field roi = f.Child("region_of_interest");
  scene.roi.min = roi.Vec<3>("min");
  scene.roi.max = roi.Vec<3>("max");
  Require((scene.roi.max.array() > scene.roi.min.array()).all(), roi, "max",
          "must exceed min in every coordinate");
  scene.mean_terrain_height = f.Number("mean_terrain_height", 0.0);
  std::string base_dir;
  if (source_name.find('/') != std::string::npos ||
      std::filesystem::exists(source_name)) {
    base_dir = std::filesystem::path(source_name).parent_path().string();
  }
  const auto shapes = f.Array("surface", true);
  Require(!shapes.empty(), f, "surface", "needs at least one shape");
  for (const Field& s : shapes) scene.surface.push_back(ParseShape(s, base_dir));

  if (f.Has("albedo")) ParseAlbedo(f.Child("albedo"), &scene.albedo);
  if (scene.albedo.wavelength_max == 0) {
    scene.albedo.wavelength_min = 2 * scene.ground_pixel_size;
    scene.albedo.wavelength_max = 20 * scene.ground_pixel_size;
  }
  if (f.Has("sun")) ParseSun(f.Child("sun"), &scene.sun);
  scene.layout = ParseLayout(f.Child("cameras"));
  ParseRendering(f, &scene);
  asked.RefuseOthers(source_name);
  scene.source_path = source_name;
  scene.Check();
  return scene;
}

Scene ParseScene(std::istream& in, const std::string& source_name) {
  nlohmann::json json;
  try {
    json = nlohmann::json::parse(in);
  } catch (const nlohmann::json::parse_error& e) {
    throw std::runtime_error(source_name + ": invalid JSON: " + e.what());
  }
  return ParseScene(json, source_name);
}

Scene LoadScene(const std::string& path) {
  std::ifstream in = OpenInputFile(path, "scene file");
  return ParseScene(in, path);
}

}  // namespace facets
