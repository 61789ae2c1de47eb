#include "scenes/renderer.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <stdexcept>

#include "io/colmap_io.h"
#include "io/image_io.h"
#include "io/output_folder.h"
#include "io/ply_io.h"
#include "io/project_io.h"
#include "scenes/camera_layout.h"

namespace facets {
namespace fs = std::filesystem;

Renderer::Renderer(const Scene& scene, const TruthMesh& mesh, EmbreeDevice& device)
    : scene_(scene),
      mesh_(mesh),
      albedo_(scene.albedo),
      sun_direction_(scene.sun.Direction()),
      embree_(std::make_unique<TriangleScene>(device, mesh.vertices, mesh.faces)) {}

SurfaceHit Renderer::Cast(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction) const {
  const Eigen::Vector3d d = direction.normalized();
  const RayHit hit = embree_->Intersect(origin, d);
  if (!hit.hit) return SurfaceHit();
  return Resolve(origin, d, static_cast<int>(hit.prim_id), hit.u, hit.v);
}

SurfaceHit Renderer::Resolve(const Eigen::Vector3d& origin, const Eigen::Vector3d& d, int face,
                             float u, float v) const {
  SurfaceHit out;
  out.hit = true;
  out.face = face;
  // Embree's float ray is ~1e-4 m off at 2 km range: intersect the double ray with
  // the plane of the face it found instead.
  const Eigen::Vector3i& F = mesh_.faces[out.face];
  const Eigen::Vector3d& v0 = mesh_.vertices[F[0]];
  const Eigen::Vector3d n = (mesh_.vertices[F[1]] - v0).cross(mesh_.vertices[F[2]] - v0);
  const double nd = n.dot(d);
  if (std::abs(nd) > 1e-12 * n.norm()) {
    out.distance = n.dot(v0 - origin) / nd;
    out.point = origin + out.distance * d;
  } else {
    out.point = mesh_.Point(out.face, u, v);
    out.distance = (out.point - origin).norm();
  }
  out.normal = mesh_.ShadingNormal(out.face, u, v);
  // Two-sided shading: a face seen from behind is lit as seen from the front.
  if (out.normal.dot(d) > 0) out.normal = -out.normal;
  return out;
}

double Renderer::Radiance(const SurfaceHit& hit) const {
  if (!hit.hit) return 0.0;
  // A cast shadow: the surface between the point and the sun. The ray starts 1 cm off
  // the point (Embree's float ray is ~1e-5 m off at the scenes' ranges of 100 m).
  const bool shadowed = scene_.sun.cast_shadows && hit.normal.dot(sun_direction_) > 0 &&
                        embree_->Occluded(hit.point, sun_direction_, 0.01f, 1e30f);
  // No direct light in the shadow: the zero vector leaves the ambient term alone.
  return 255.0 * LambertShading(albedo_(hit.point), hit.normal, scene_.sun,
                                shadowed ? Eigen::Vector3d::Zero() : sun_direction_);
}

double Renderer::RadianceAtPixel(const Camera& camera, const BlockImage& image,
                                 const Eigen::Vector2d& pixel) const {
  const Eigen::Vector3d dir = image.cam_from_world.rotation.conjugate() * camera.CamFromImage(pixel);
  return Radiance(Cast(image.ProjectionCentre(), dir));
}

std::vector<float> Renderer::RenderClean(const Camera& camera, const BlockImage& image,
                                         int supersampling) const {
  const int w = camera.width, h = camera.height, S = supersampling;
  std::vector<float> out(static_cast<size_t>(w) * h, 0.0f);
  const Eigen::Matrix3d world_from_cam = image.cam_from_world.rotation.conjugate().toRotationMatrix();
  const Eigen::Vector3d centre = image.ProjectionCentre();
  const RTCScene rtc_scene = embree_->get();
  tbb::parallel_for(tbb::blocked_range<int>(0, h), [&](const tbb::blocked_range<int>& rows) {
    // One row of pixels = w * S * S rays, traced as one coherent stream (Embree's
    // rtcIntersect1M: packets inside; half the CPU time of single rays here).
    std::vector<RTCRayHit> rays(static_cast<size_t>(w) * S * S);
    std::vector<Eigen::Vector3d> dirs(rays.size());
    for (int y = rows.begin(); y < rows.end(); ++y) {
      size_t r = 0;
      for (int x = 0; x < w; ++x) {
        for (int j = 0; j < S; ++j) {
          for (int i = 0; i < S; ++i, ++r) {
            const Eigen::Vector2d px(x + (i + 0.5) / S, y + (j + 0.5) / S);
            dirs[r] = (world_from_cam * camera.CamFromImage(px)).normalized();
            RTCRayHit& rh = rays[r];
            rh.ray.org_x = static_cast<float>(centre.x());
            rh.ray.org_y = static_cast<float>(centre.y());
            rh.ray.org_z = static_cast<float>(centre.z());
            rh.ray.dir_x = static_cast<float>(dirs[r].x());
            rh.ray.dir_y = static_cast<float>(dirs[r].y());
            rh.ray.dir_z = static_cast<float>(dirs[r].z());
            rh.ray.tnear = 0.0f;
            rh.ray.tfar = 1e30f;
            rh.ray.mask = ~0u;
            rh.ray.flags = 0;
            rh.ray.time = 0;
            rh.ray.id = static_cast<unsigned>(r);
            rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
            rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
          }
        }
      }
      RTCIntersectContext context;
      rtcInitIntersectContext(&context);
      context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
      rtcIntersect1M(rtc_scene, &context, rays.data(), static_cast<unsigned>(rays.size()),
                     sizeof(RTCRayHit));
      r = 0;
      for (int x = 0; x < w; ++x) {
        double sum = 0;
        for (int k = 0; k < S * S; ++k, ++r) {
          const RTCRayHit& rh = rays[r];
          if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) continue;
          sum += Radiance(Resolve(centre, dirs[r], static_cast<int>(rh.hit.primID), rh.hit.u,
                                  rh.hit.v));
        }
        out[static_cast<size_t>(y) * w + x] = static_cast<float>(sum / (S * S));
      }
    }
  });
  return out;
}

std::vector<uint8_t> AddNoiseAndQuantise(const std::vector<float>& clean, double sigma,
                                         uint32_t seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, sigma > 0 ? sigma : 1.0);
  std::vector<uint8_t> out(clean.size());
  for (size_t i = 0; i < clean.size(); ++i) {
    const double g = clean[i] + (sigma > 0 ? noise(rng) : 0.0);
    out[i] = static_cast<uint8_t>(std::clamp(std::lround(g), 0L, 255L));
  }
  return out;
}

namespace {

// Faces whose centroid lies in the ROI with the running sum of their areas (m^2), for
// drawing a face with probability proportional to its area.
struct AreaTable {
  std::vector<int> faces;
  std::vector<double> cumulative;
  double total = 0;
};

AreaTable RoiFacesByArea(const Scene& scene, const TruthMesh& mesh) {
  AreaTable table;
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    const Eigen::Vector3i& F = mesh.faces[f];
    const Eigen::Vector3d centroid =
        (mesh.vertices[F[0]] + mesh.vertices[F[1]] + mesh.vertices[F[2]]) / 3;
    if (!scene.roi.Contains(centroid)) continue;
    table.total += 0.5 * (mesh.vertices[F[1]] - mesh.vertices[F[0]])
                             .cross(mesh.vertices[F[2]] - mesh.vertices[F[0]])
                             .norm();
    table.faces.push_back(static_cast<int>(f));
    table.cumulative.push_back(table.total);
  }
  return table;
}

// The images (index, pixel) that see p: inside the frame by a pixel, the first hit of
// the ray is p itself, and the ray is not grazing.
std::vector<std::pair<size_t, Eigen::Vector2d>> ImagesSeeing(const Eigen::Vector3d& p,
                                                             const ImageBlock& block,
                                                             const Renderer& renderer) {
  std::vector<std::pair<size_t, Eigen::Vector2d>> seen;
  for (size_t k = 0; k < block.images.size(); ++k) {
    const BlockImage& image = block.images[k];
    const Camera& camera = block.CameraOf(image);
    const Eigen::Vector3d pc = image.cam_from_world * p;
    if (pc.z() <= 0) continue;
    const Eigen::Vector2d px = camera.ImageFromCam(pc);
    if (px.x() < 1 || px.y() < 1 || px.x() > camera.width - 1 || px.y() > camera.height - 1) {
      continue;
    }
    const Eigen::Vector3d c = image.ProjectionCentre();
    const double range = (p - c).norm();
    const SurfaceHit hit = renderer.Cast(c, p - c);
    // Visible: the first hit is the point itself (float ray, double point).
    if (!hit.hit || std::abs(hit.distance - range) > 0.01 + 1e-5 * range) continue;
    // Not at grazing incidence, where a matcher would not find it either.
    if (std::abs(hit.normal.dot((p - c) / range)) < 0.2) continue;
    seen.emplace_back(k, px);
  }
  return seen;
}

// A tie point at truth point p seen by `seen`: its start xyz perturbed by tie_point_sigma
// (m; the 3D offset truncated at 2 sigma), its grey from the first image, its track and
// keypoints added to the images, its error the mean reprojection distance (px).
TiePoint MakeTiePoint(const Eigen::Vector3d& p,
                      const std::vector<std::pair<size_t, Eigen::Vector2d>>& seen, long long id,
                      double sigma, const Renderer& renderer, std::normal_distribution<double>& gauss,
                      std::mt19937& rng, ImageBlock* block) {
  TiePoint tie;
  tie.point3d_id = id;
  Eigen::Vector3d e;
  do {
    e = Eigen::Vector3d(gauss(rng), gauss(rng), gauss(rng));
  } while (e.norm() > 2);
  tie.xyz = p + sigma * e;
  SurfaceHit on_surface = renderer.Cast(block->images[seen[0].first].ProjectionCentre(),
                                        p - block->images[seen[0].first].ProjectionCentre());
  const int grey = static_cast<int>(std::lround(std::clamp(renderer.Radiance(on_surface), 0.0, 255.0)));
  tie.rgb = Eigen::Vector3i(grey, grey, grey);
  double error = 0;
  for (const auto& [k, px] : seen) {
    BlockImage& image = block->images[k];
    const Eigen::Vector2d reprojected =
        block->CameraOf(image).ImageFromCam(image.cam_from_world * tie.xyz);
    error += (reprojected - px).norm();
    tie.track.push_back({image.image_id, static_cast<int>(image.keypoints.size())});
    image.keypoints.push_back({px, tie.point3d_id});
  }
  tie.error = error / seen.size();
  return tie;
}

}  // namespace

int SampleTiePoints(const Scene& scene, const TruthMesh& mesh, const Renderer& renderer,
                    uint32_t seed, ImageBlock* block) {
  const AreaTable table = RoiFacesByArea(scene, mesh);
  if (table.faces.empty() || scene.tie_points == 0) return 0;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::normal_distribution<double> gauss(0.0, 1.0);
  long long next_id = 1;
  const int max_attempts = 30 * scene.tie_points;
  for (int attempt = 0; attempt < max_attempts &&
                        static_cast<int>(block->points.size()) < scene.tie_points;
       ++attempt) {
    const double r = unit(rng) * table.total;
    const int f = table.faces[std::lower_bound(table.cumulative.begin(), table.cumulative.end(),
                                               r) -
                              table.cumulative.begin()];
    double a = unit(rng), b = unit(rng);
    if (a + b > 1) {
      a = 1 - a;
      b = 1 - b;
    }
    const Eigen::Vector3d p = mesh.Point(f, a, b);
    const auto seen = ImagesSeeing(p, *block, renderer);
    if (seen.size() < 2) continue;
    // Start values, not truth: the tie point is perturbed.
    block->points.push_back(MakeTiePoint(p, seen, next_id++, scene.tie_point_sigma, renderer,
                                         gauss, rng, block));
  }
  return static_cast<int>(block->points.size());
}

namespace {

void WriteTruthJson(const Scene& scene, const ImageBlock& block, const TruthMesh& mesh,
                    const std::string& path) {
  nlohmann::json j;
  j["scene"] = scene.name;
  j["ground_pixel_size"] = scene.ground_pixel_size;
  j["region_of_interest"] = {{"min", {scene.roi.min.x(), scene.roi.min.y(), scene.roi.min.z()}},
                             {"max", {scene.roi.max.x(), scene.roi.max.y(), scene.roi.max.z()}}};
  j["labels"] = {{"0", "ground"}, {"1", "roof"}, {"2", "wall"}, {"3", "object"}};
  j["noise_sigma"] = scene.noise_sigma;
  j["supersampling"] = scene.supersampling;
  j["seed"] = scene.seed;
  j["mean_terrain_height"] = scene.mean_terrain_height;
  j["images"] = block.images.size();
  j["tie_points"] = block.points.size();
  j["truth_mesh"] = {{"file", "truth.ply"},
                     {"vertices", mesh.vertices.size()},
                     {"faces", mesh.faces.size()},
                     {"sagitta_tolerance", scene.sagitta_tolerance}};
  nlohmann::json shapes = nlohmann::json::array();
  if (scene.json.contains("surface")) shapes = scene.json["surface"];
  j["shapes"] = shapes;
  j["sun"] = {{"azimuth_deg", scene.sun.azimuth_deg},
              {"elevation_deg", scene.sun.elevation_deg},
              {"ambient", scene.sun.ambient},
              {"cast_shadows", scene.sun.cast_shadows}};
  std::ofstream out(path);
  out << j.dump(2) << "\n";
  if (!out) throw std::runtime_error(path + ": cannot write");
}

}  // namespace

RenderSummary RenderSceneInto(const Scene& scene_in, const std::string& dir, const RenderOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  Scene scene = scene_in;
  if (options.seed) scene.seed = *options.seed;
  if (options.noise_sigma) scene.noise_sigma = *options.noise_sigma;
  if (options.supersampling) scene.supersampling = *options.supersampling;
  scene.json["seed"] = scene.seed;
  scene.json["noise_sigma"] = scene.noise_sigma;
  scene.json["supersampling"] = scene.supersampling;
  scene.Check();

  const TruthMesh mesh = BuildTruthMesh(scene);
  ImageBlock block = BuildImageBlock(scene);
  const Renderer renderer(scene, mesh);
  RenderSummary summary;
  summary.triangles = static_cast<int>(mesh.faces.size());
  summary.tie_points =
      SampleTiePoints(scene, mesh, renderer, static_cast<uint32_t>(scene.seed) * 7u + 1u, &block);

  const fs::path out(dir);
  fs::create_directories(out / "images");
  for (size_t i = 0; i < block.images.size(); ++i) {
    BlockImage& image = block.images[i];
    const Camera& camera = block.CameraOf(image);
    const auto r0 = std::chrono::steady_clock::now();
    const std::vector<float> clean = renderer.RenderClean(camera, image, scene.supersampling);
    summary.render_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - r0).count();
    const std::vector<uint8_t> grey = AddNoiseAndQuantise(
        clean, scene.noise_sigma, static_cast<uint32_t>(scene.seed) * 1000003u + static_cast<uint32_t>(image.image_id));
    ImagePlanes planes;
    planes.width = camera.width;
    planes.height = camera.height;
    planes.channels = 1;
    planes.bits = 8;
    planes.data.assign(grey.begin(), grey.end());
    // The project file stores the path relative to itself.
    image.path = (out / "images" / image.name).string();
    WriteImage(image.path, planes, 8);
    summary.pixels += static_cast<long long>(camera.width) * camera.height;
    ++summary.images;
    if (options.progress) options.progress(static_cast<int>(i) + 1, static_cast<int>(block.images.size()), image.name);
  }
  WriteColmapModel(block, (out / "sparse").string());
  WriteProject(block, (out / "project.json").string());
  WritePly((out / "truth.ply").string(), mesh.ToMeshData());
  WriteTruthJson(scene, block, mesh, (out / "truth.json").string());
  {
    std::ofstream copy(out / "scene.json");
    copy << scene.json.dump(2) << "\n";
    if (!copy) throw std::runtime_error((out / "scene.json").string() + ": cannot write");
  }
  summary.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return summary;
}

RenderSummary RenderScene(const Scene& scene, const std::string& out_dir, const RenderOptions& options) {
  OutputFolder output(out_dir, OutputFolder::Start::kEmpty);
  RenderSummary summary;
  try {
    summary = RenderSceneInto(scene, output.path(), options);
  } catch (const std::runtime_error& e) {
    throw std::runtime_error(output.InFinalNames(e.what()));
  }
  output.Commit();
  return summary;
}

}  // namespace facets
