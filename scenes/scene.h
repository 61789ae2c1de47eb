// A synthetic scene description: analytic surface, albedo, sun, camera layout and the
// rendering parameters. Parsed from JSON (format in docs/SCENES.md); every parse error
// names the file and the JSON path of the bad field ("block.json: /surface/2/width:
// expected a number").
//
// Units: metres and degrees in object space, millimetres for focal lengths,
// micrometres for pixel pitches. Object coordinates are local (the scene is built
// around the origin), Z up.
#pragma once

#include <Eigen/Core>
#include <istream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "io/image_block.h"

namespace facets {

// Region labels of the truth mesh (per face).
enum RegionLabel : int { kLabelGround = 0, kLabelRoof = 1, kLabelWall = 2, kLabelObject = 3 };
std::string RegionLabelName(int label);

enum class ShapeType {
  kTerrain,             // height field z = base + sum of gentle sinusoids
  kPlane,               // horizontal rectangle (optionally rotated about Z)
  kGableRoof,           // two planes meeting at a ridge (seed surfaces 1 and 2)
  kParabolicCylinder,   // parabola moved along a horizontal line (seed surfaces 3, 4)
  kBuilding,            // walls from below the terrain to the eaves + flat/gable/hip roof
  kBlob,                // closed star-shaped deformed sphere (close range)
  kMesh,                // triangle mesh file (PLY/OBJ)
};

enum class RoofType { kFlat, kGable, kHip };

// One analytic shape. Which fields matter depends on `type` (docs/SCENES.md).
struct Shape {
  ShapeType type = ShapeType::kPlane;
  int label = kLabelGround;          // region label of its faces (walls get kLabelWall)
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  double azimuth_deg = 0;            // rotation about Z, counter-clockwise from +X
  double length = 10;                // along the rotated X axis (ridge direction)
  double width = 10;                 // along the rotated Y axis
  double slope_deg = 20;             // roof plane inclination (gable, hip roofs)
  double height = 3;                 // parabola height (cylinder), eave height (building)
  double step = 0;                   // mesh edge length; 0 = chosen from tolerance
  // Terrain: list of (amplitude m, wavelength m, direction deg, phase deg).
  std::vector<Eigen::Vector4d> waves;
  // Building.
  RoofType roof = RoofType::kFlat;
  // Outward lean of the four walls (deg): +X side, +Y side, -X side, -Y side in the
  // building frame. A positive lean displaces the top edge outward (an overhang).
  Eigen::Vector4d wall_lean_deg = Eigen::Vector4d::Zero();
  // Blob: r(u) = radius * (1 + lobe_amplitude * sum_i w_i sin(f_i u.d_i + p_i)) for a
  // unit direction u; d_i, f_i, p_i drawn from lobes_seed, weights sum to 1.
  double radius = 1;
  int lobes_seed = 1;
  double lobe_amplitude = 0.15;
  // Mesh file (resolved relative to the scene file).
  std::string mesh_path;
};

// Constant-albedo patch: an XY rectangle (rotated by azimuth about its centre) over
// all heights, or a 3D axis-aligned box when `box` is true.
struct AlbedoPatch {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  Eigen::Vector3d size = Eigen::Vector3d(8, 6, 0);  // z ignored for rectangles
  double azimuth_deg = 0;
  bool box = false;
  double albedo = 0.5;
  bool Contains(const Eigen::Vector3d& p) const;
};

// A further texture band added to the main one (own components, own contrast).
struct AlbedoBand {
  double wavelength_min = 0;    // m
  double wavelength_max = 0;    // m
  double contrast = 0.1;        // standard deviation of this band alone
  int components = 16;
};

struct AlbedoOptions {
  int seed = 1;
  int components = 32;          // random 3D sinusoids
  // Wavelength band of the texture (m). 0 = 2 and 20 ground pixels.
  double wavelength_min = 0;
  double wavelength_max = 0;
  double mean = 0.5;            // mean albedo
  double contrast = 0.18;       // standard deviation of the albedo before clamping
  // Added after the main band from their own random streams, so a scene without them
  // renders exactly as before. Use: long wavelengths for the coarse pyramid levels
  // without weakening the short ones the finest level matches.
  std::vector<AlbedoBand> extra_bands;
  std::vector<AlbedoPatch> patches;
};

struct SunOptions {
  double azimuth_deg = 135;     // clockwise from +Y (north) towards +X (east)
  double elevation_deg = 50;
  double ambient = 0.2;         // share of diffuse sky light, 0..1
  // Points whose ray towards the sun hits the surface get the ambient light only.
  bool cast_shadows = false;
  Eigen::Vector3d Direction() const;  // unit vector towards the sun
};

enum class LayoutType { kStereo, kBlock, kRing, kList };

struct ExplicitCamera {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  Eigen::Vector3d target = Eigen::Vector3d::Zero();
  Eigen::Vector3d up = Eigen::Vector3d::UnitY();
};

struct RingSpec {
  double radius = 3;
  double elevation_deg = 20;
  int count = 12;
  double azimuth_offset_deg = 0;
};

struct CameraLayout {
  LayoutType type = LayoutType::kStereo;
  double focal_mm = 153;
  double pixel_um = 20;
  int width = 0, height = 0;      // pixels (stereo: 0 = full frame / crop)
  double frame_mm = 230;          // stereo: square film frame
  double flying_height = 1800;    // above reference_height
  double reference_height = 0;    // Z of the mean terrain
  double overlap = 0.6;           // stereo forward overlap
  double forward_overlap = 0.7;   // block
  double side_overlap = 0.7;      // block
  int rows = 3, cols = 3;         // block strips x images per strip
  int obliques = 4;               // block: looking N, E, S, W at the block centre
  double oblique_tilt_deg = 40;   // off nadir
  // Obliques per direction, side by side along a strip across the viewing direction with
  // parallel axes (a multi-camera rig flown along a line), oblique_base apart
  // (0 = the nadir forward base). One per direction sees each wall once: too few to
  // intersect a wall (its depth is then decided by the regularisation alone).
  int oblique_strip = 1;
  double oblique_base = 0;        // m
  // Every oblique aimed at the target instead (a strip of cameras converging on the
  // block centre, as when one camera is flown past it several times).
  bool oblique_convergent = false;
  Eigen::Vector3d target = Eigen::Vector3d::Zero();  // block centre / ring target
  std::vector<RingSpec> rings;
  std::vector<ExplicitCamera> cameras;
  // Crop every frame to the region of interest plus a margin (seed stereo pairs).
  bool crop_to_roi = false;
  int crop_margin_px = 40;
};

struct Scene {
  std::string name;
  std::string source_path;        // file the scene came from ("" for strings)
  nlohmann::json json;            // the parsed description, copied to the output
  double ground_pixel_size = 0.1; // m, used by evaluation and texture defaults
  RegionOfInterest roi;
  double mean_terrain_height = 0;
  std::vector<Shape> surface;
  AlbedoOptions albedo;
  SunOptions sun;
  CameraLayout layout;
  double noise_sigma = 4;
  int supersampling = 3;          // S x S sub-samples per pixel (box filter)
  int seed = 1;
  // Truth-mesh discretisation tolerance for curved shapes (max sagitta, m).
  double sagitta_tolerance = 0.001;
  int tie_points = 300;           // target count of sampled tie points
  double tie_point_sigma = 0;     // perturbation (m); 0 = a quarter ground pixel

  // Throws std::invalid_argument naming the field when a value is out of range.
  void Check() const;
};

// Throws std::runtime_error / std::invalid_argument naming the file and JSON path.
Scene LoadScene(const std::string& path);
Scene ParseScene(std::istream& in, const std::string& source_name = "<stream>");
Scene ParseScene(const nlohmann::json& json, const std::string& source_name);

}  // namespace facets
