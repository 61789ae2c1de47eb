#include "engine/pipeline/scene_preset.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <vector>

namespace facets {
namespace {

constexpr double kPi = 3.14159265358979323846;

double Quantile(std::vector<double> v, double q) {
  std::sort(v.begin(), v.end());
  return v[static_cast<size_t>(std::clamp(q, 0.0, 1.0) * (v.size() - 1))];
}

// The cameras' mean up direction (minus their y axes) when it is at least half a unit
// long (upright images), else +Z (nadir images flown in all directions cancel out).
Eigen::Vector3d SceneUp(const ImageBlock& block) {
  Eigen::Vector3d up = Eigen::Vector3d::Zero();
  for (const auto& image : block.images) up -= image.cam_from_world.rotation.conjugate() * Eigen::Vector3d::UnitY();
  up /= static_cast<double>(std::max<size_t>(1, block.images.size()));
  return up.norm() >= 0.5 ? Eigen::Vector3d(up.normalized()) : Eigen::Vector3d::UnitZ();
}

// Centre of the tie points (per-axis medians), else of the projection centres' footprint.
Eigen::Vector3d SceneCentre(const ImageBlock& block) {
  if (block.points.size() < 10) {
    if (block.roi) return 0.5 * (block.roi->min + block.roi->max);
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (const auto& image : block.images) mean += image.ProjectionCentre();
    return mean / static_cast<double>(std::max<size_t>(1, block.images.size()));
  }
  std::vector<double> x, y, z;
  for (const auto& p : block.points) {
    x.push_back(p.xyz.x());
    y.push_back(p.xyz.y());
    z.push_back(p.xyz.z());
  }
  return {Quantile(x, 0.5), Quantile(y, 0.5), Quantile(z, 0.5)};
}

// Spread of the tie points along up and across it (2nd to 98th percentile), m.
std::pair<double, double> TiePointSpread(const ImageBlock& block, const Eigen::Vector3d& up) {
  if (block.points.size() < 10) return {0.0, 0.0};
  const Eigen::Vector3d across_u = up.unitOrthogonal(), across_v = up.cross(across_u);
  std::vector<double> along, u, v;
  for (const auto& p : block.points) {
    along.push_back(p.xyz.dot(up));
    u.push_back(p.xyz.dot(across_u));
    v.push_back(p.xyz.dot(across_v));
  }
  const double vertical = Quantile(along, 0.98) - Quantile(along, 0.02);
  const double horizontal = std::max(Quantile(u, 0.98) - Quantile(u, 0.02), Quantile(v, 0.98) - Quantile(v, 0.02));
  return {vertical, horizontal};
}

// Largest gap between the cameras' azimuths about up, seen from the centre (deg).
double LargestAzimuthGap(const ImageBlock& block, const Eigen::Vector3d& centre, const Eigen::Vector3d& up) {
  const Eigen::Vector3d across_u = up.unitOrthogonal(), across_v = up.cross(across_u);
  std::vector<double> azimuths;
  for (const auto& image : block.images) {
    const Eigen::Vector3d d = image.ProjectionCentre() - centre;
    azimuths.push_back(std::atan2(d.dot(across_v), d.dot(across_u)) * 180.0 / kPi);
  }
  std::sort(azimuths.begin(), azimuths.end());
  double gap = azimuths.front() + 360.0 - azimuths.back();
  for (size_t k = 1; k < azimuths.size(); ++k) gap = std::max(gap, azimuths[k] - azimuths[k - 1]);
  return gap;
}

// Mean of the cameras' unit viewing directions (their z axes in the world).
Eigen::Vector3d MeanViewDirection(const ImageBlock& block) {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& image : block.images) mean += image.cam_from_world.rotation.conjugate() * Eigen::Vector3d::UnitZ();
  return mean / static_cast<double>(block.images.size());
}

}  // namespace

ScenePreset ParseScenePreset(const std::string& name) {
  if (name == "auto") return ScenePreset::kAuto;
  if (name == "aerial") return ScenePreset::kAerial;
  if (name == "facade") return ScenePreset::kFacade;
  if (name == "object") return ScenePreset::kObject;
  throw std::invalid_argument("scene preset must be auto, aerial, facade or object, not '" + name + "'");
}

std::string ScenePresetName(ScenePreset preset) {
  switch (preset) {
    case ScenePreset::kAerial: return "aerial";
    case ScenePreset::kFacade: return "facade";
    case ScenePreset::kObject: return "object";
    case ScenePreset::kAuto: break;
  }
  return "auto";
}

ScenePreset ChooseScenePreset(const ImageBlock& block, std::string* why) {
  if (block.images.empty()) throw std::invalid_argument("choosing a scene preset: the block has no images");
  // Aerial: the images look down the model's Z (georeferenced blocks have Z up) onto tie
  // points spread less than half as far along Z as across it.
  const Eigen::Vector3d view = MeanViewDirection(block);
  const double off_nadir = std::acos(std::clamp(-view.normalized().z(), -1.0, 1.0)) * 180.0 / kPi;
  const auto [height, width] = TiePointSpread(block, Eigen::Vector3d::UnitZ());
  const bool flat = width > 0.0 ? height < 0.5 * width : true;
  // Object: the images look from all sides (their viewing directions cancel out to less
  // than half a unit), or the cameras surround the tie points' centre about the scene's
  // up (the cameras' mean up when they agree on one, else Z).
  const Eigen::Vector3d up = SceneUp(block);
  const Eigen::Vector3d centre = SceneCentre(block);
  const double gap = LargestAzimuthGap(block, centre, up);
  ScenePreset preset = ScenePreset::kFacade;
  if (view.norm() > 0.7 && off_nadir < 45.0 && flat) {
    preset = ScenePreset::kAerial;
  } else if (view.norm() < 0.5 || gap < 150.0) {
    preset = ScenePreset::kObject;
  }
  if (why) {
    std::ostringstream line;
    line.precision(3);
    line << "mean view " << off_nadir << " deg off nadir (length " << view.norm() << "), tie points " << height
         << " m high against " << width << " m wide, largest gap between the cameras' azimuths " << gap
         << " deg";
    *why = line.str();
  }
  return preset;
}

void ApplyScenePreset(ScenePreset preset, ReconstructionOptions* options) {
  switch (preset) {
    case ScenePreset::kAerial:
      options->levels = 4;
      options->facet_pixels = 1.5;
      options->v_cycles = 1;
      options->v_cycle_rounds_last_level = 0;
      // Search rounds kept whatever sigma0 does, not judged: a round moves a few hundred wall
      // vertices among millions of observations, sigma0 moves by a few tenths of a percent
      // either way, and judging it dropped rounds that stood walls up.
      options->normal_search_tolerance = 1.0;
      options->normal_search_local_rings = 1;
      options->wall_corners = true;
      options->wall_feet = true;
      options->wall_eaves = true;
      // Two flat iterations end a window run: the aerial path's windows and trials stall at
      // walls and eaves the level cannot represent; the seed scenes' windows keep the
      // library's 4 (one step may grow once before they converge).
      options->adjustment.stall_iterations = 2;
      // One face ring around a window's core (a core vertex's whole 1-ring): a level-0
      // window of about 230 core faces then covers about 1.3 instead of 1.6 times their
      // area, so every iteration casts and linearises a fifth fewer pixels.
      options->windows.partition.margin_rings = 1;
      break;
    case ScenePreset::kFacade:
      options->start_plane = ReconstructionOptions::StartPlane::kFitted;
      break;
    case ScenePreset::kObject:
      options->start_closed = true;
      options->closed.shape = "visual-hull";
      options->levels = 2;
      options->adjustment.max_iterations = 4;
      options->adjustment.robust_k = 2.0;
      options->adjustment.reject_k = 5.0;
      options->adjustment.silhouette_weight = 10000.0;
      options->adjustment.silhouette_inside_px = 4.0;
      options->closed.clamp_guard = true;
      break;
    case ScenePreset::kAuto:
      break;
  }
}

}  // namespace facets
