// The renderer of synthetic scenes: first-hit ray casting with Embree, S x S
// supersampling (box filter), Lambertian sun shading of the procedural albedo,
// white Gaussian noise, 8-bit quantisation; and RenderScene, which writes the whole
// data set (images, COLMAP model, project file, truth mesh and parameters).
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "io/image_block.h"
#include "scenes/albedo.h"
#include "scenes/scene.h"
#include "scenes/truth_mesh.h"
#include "visibility/embree_scene.h"

namespace facets {

struct SurfaceHit {
  bool hit = false;
  int face = -1;
  double distance = 0;            // along the unit ray direction, m
  Eigen::Vector3d point;          // on the truth mesh (double, from barycentrics)
  Eigen::Vector3d normal;         // unit shading normal, facing the ray
};

class Renderer {
 public:
  // Keeps references to scene and mesh: both must outlive the renderer.
  Renderer(const Scene& scene, const TruthMesh& mesh,
           EmbreeDevice& device = EmbreeDevice::Shared());

  // First hit of a ray (direction need not be unit).
  SurfaceHit Cast(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction) const;
  // Noise-free grey value 255 * albedo * shading at a hit (0 for no hit).
  double Radiance(const SurfaceHit& hit) const;
  // Radiance of the ray through a pixel position (pixel convention of io/camera.h).
  double RadianceAtPixel(const Camera& camera, const BlockImage& image,
                         const Eigen::Vector2d& pixel) const;
  // Noise-free image, row-major width x height, S x S box-filtered sub-samples, rows
  // in parallel (TBB). Deterministic.
  std::vector<float> RenderClean(const Camera& camera, const BlockImage& image,
                                 int supersampling) const;

  const ProceduralAlbedo& albedo() const { return albedo_; }

 private:
  // Hit record from Embree's face and barycentrics for the unit ray (origin, d).
  SurfaceHit Resolve(const Eigen::Vector3d& origin, const Eigen::Vector3d& d, int face,
                     float u, float v) const;

  const Scene& scene_;
  const TruthMesh& mesh_;
  ProceduralAlbedo albedo_;
  Eigen::Vector3d sun_direction_;
  std::unique_ptr<TriangleScene> embree_;
};

// Adds N(0, sigma^2) noise (std::mt19937 seeded with `seed`), rounds and clamps to
// 0..255.
std::vector<uint8_t> AddNoiseAndQuantise(const std::vector<float>& clean, double sigma,
                                         uint32_t seed);

// Samples up to scene.tie_points points on the truth surface inside the ROI that are
// visible (first hit) in at least 2 images, stores their observations as keypoints of
// the images (exact projections) and the tracks in block->points; xyz perturbed by
// N(0, tie_point_sigma^2) per coordinate, the 3D offset truncated at 2 sigma (start
// values, not truth). Returns the count.
int SampleTiePoints(const Scene& scene, const TruthMesh& mesh, const Renderer& renderer,
                    uint32_t seed, ImageBlock* block);

struct RenderOptions {
  std::optional<int> seed;            // overrides Scene::seed (noise, tie points)
  std::optional<double> noise_sigma;  // overrides Scene::noise_sigma
  std::optional<int> supersampling;   // overrides Scene::supersampling
  // Called after each image: (index 1..N, N, image name).
  std::function<void(int, int, const std::string&)> progress;
};

struct RenderSummary {
  int images = 0;
  long long pixels = 0;
  int triangles = 0;
  int tie_points = 0;
  double seconds = 0;        // wall time of the whole run
  double render_seconds = 0; // ray casting and shading only
};

// Writes into the folder `dir` (created when missing): images/img_NN.png,
// sparse/{cameras,images,points3D}.txt, project.json, truth.ply (face labels),
// truth.json, scene.json.
RenderSummary RenderSceneInto(const Scene& scene, const std::string& dir, const RenderOptions& options = {});

// RenderSceneInto out_dir as a unit (io/output_folder.h): written into a temporary folder
// beside it that replaces out_dir (a previous output as a whole) only when complete; a
// failure leaves out_dir as it was.
RenderSummary RenderScene(const Scene& scene, const std::string& out_dir, const RenderOptions& options = {});

}  // namespace facets
