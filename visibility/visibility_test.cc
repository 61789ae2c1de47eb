#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <iostream>
#include <limits>
#include <memory>
#include <random>
#include <set>

#include "visibility/image_selection.h"
#include "visibility/pixel_cast.h"
#include "visibility/surface_scene.h"
#include "visibility/test_util.h"
#include "visibility/visibility_map.h"

namespace facets {
namespace {

// cam_from_world of a camera at `centre` looking at `target`, image up ~ world +z
// (COLMAP frame: x right, y down, z forward).
Rigid3d LookAt(const Eigen::Vector3d& centre, const Eigen::Vector3d& target,
               const Eigen::Vector3d& up = Eigen::Vector3d::UnitZ()) {
  const Eigen::Vector3d z = (target - centre).normalized();
  const Eigen::Vector3d x = z.cross(up).normalized();
  const Eigen::Vector3d y = z.cross(x);
  Eigen::Matrix3d world_from_cam;
  world_from_cam << x, y, z;
  const Eigen::Matrix3d cam_from_world = world_from_cam.transpose();
  return Rigid3d(Eigen::Quaterniond(cam_from_world), -(cam_from_world * centre));
}

Camera PinholeCamera(int width, int height, double focal) {
  return Camera::Create(CameraModel::kPinhole, focal, focal, 0.5 * width, 0.5 * height,
                        width, height);
}

// Ground [-10, 10]^2 at z = 0 (ground_cells^2 quads) plus a box standing on it.
FlatMesh GroundWithBox(const Eigen::Vector3d& box_min, const Eigen::Vector3d& box_max,
                       int ground_cells, int* num_ground_faces) {
  FlatMesh mesh;
  AppendGridForTesting(-10, -10, 10, 10, ground_cells, ground_cells,
                       [](double, double) { return 0.0; }, &mesh);
  *num_ground_faces = static_cast<int>(mesh.faces.size());
  AppendBoxForTesting(box_min, box_max, /*with_bottom=*/false, &mesh);
  return mesh;
}

// First hit of a ray against every sub-triangle (Moeller-Trumbore in double on the
// float-rounded vertices Embree sees). Returns facet or -1; t, barycentrics (u, v)
// and the distance of the hit to the nearest facet edge in barycentric units.
struct BruteHit {
  int facet = -1;
  double t = std::numeric_limits<double>::infinity();
  double u = 0, v = 0;
  double edge = 0;
};

BruteHit BruteForce(const Tessellation& tess, const Eigen::Vector3d& origin,
                    const Eigen::Vector3d& direction) {
  BruteHit best;
  for (int s = 0; s < static_cast<int>(tess.triangles.size()); ++s) {
    const Eigen::Vector3i& tri = tess.triangles[s];
    const Eigen::Vector3d p0 = tess.points[tri[0]].cast<float>().cast<double>();
    const Eigen::Vector3d p1 = tess.points[tri[1]].cast<float>().cast<double>();
    const Eigen::Vector3d p2 = tess.points[tri[2]].cast<float>().cast<double>();
    const Eigen::Vector3d e1 = p1 - p0, e2 = p2 - p0;
    const Eigen::Vector3d pvec = direction.cross(e2);
    const double det = e1.dot(pvec);
    if (std::fabs(det) < 1e-300) continue;
    const Eigen::Vector3d tvec = origin - p0;
    const double u = tvec.dot(pvec) / det;
    if (u < 0 || u > 1) continue;
    const Eigen::Vector3d qvec = tvec.cross(e1);
    const double v = direction.dot(qvec) / det;
    if (v < 0 || u + v > 1) continue;
    const double t = e2.dot(qvec) / det;
    if (t <= 0 || t >= best.t) continue;
    best = {s, t, u, v, std::min({u, v, 1.0 - u - v})};
  }
  return best;
}

// Where the ray enters the box, or +inf.
double RayBoxEntry(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                   const Eigen::AlignedBox3d& box) {
  double t0 = 0, t1 = std::numeric_limits<double>::infinity();
  for (int a = 0; a < 3; ++a) {
    const double inv = 1.0 / direction[a];
    double ta = (box.min()[a] - origin[a]) * inv, tb = (box.max()[a] - origin[a]) * inv;
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
  }
  return t0 <= t1 ? t0 : std::numeric_limits<double>::infinity();
}

TEST(SurfaceScene, UpdateMovesVerticesInPlaceAndRebuildsOnNewTopology) {
  FlatMesh mesh;
  AppendGridForTesting(-10, -10, 10, 10, 4, 4, [](double, double) { return 0.0; }, &mesh);
  Tessellation tess = TessellateFlatForTesting(mesh);
  SurfaceScene scene(tess);
  EXPECT_EQ(scene.NumFacets(), 32 * 16);
  EXPECT_EQ(scene.NumBuilds(), 1);
  const Camera camera = PinholeCamera(64, 48, 60);
  const Rigid3d pose = LookAt({0, 0, 10}, {0, 0, 0}, Eigen::Vector3d::UnitY());
  const CastResult before = CastPixels(scene, camera, pose, PixelRect::Full(camera));
  for (Eigen::Vector3d& p : tess.points) p.z() += 1.0;
  EXPECT_EQ(scene.Update(tess), SurfaceScene::UpdateKind::kMovedVertices);
  EXPECT_EQ(scene.NumBuilds(), 1);
  const CastResult after = CastPixels(scene, camera, pose, PixelRect::Full(camera));
  ASSERT_EQ(before.observations.size(), after.observations.size());
  double max_error = 0;
  for (size_t i = 0; i < after.observations.size(); ++i) {
    // Plane z = 0 -> z = 1 seen from z = 10: distances shrink by the factor 9/10.
    max_error = std::max<double>(max_error, std::fabs(after.observations[i].distance -
                                                      0.9 * before.observations[i].distance));
  }
  // A static (non-refittable) scene rebuilds its BVH in place: same answers.
  SurfaceScene static_scene(tess, /*refittable=*/false);
  EXPECT_EQ(static_scene.Update(tess), SurfaceScene::UpdateKind::kMovedVertices);
  const CastResult from_static = CastPixels(static_scene, camera, pose, PixelRect::Full(camera));
  ASSERT_EQ(from_static.observations.size(), after.observations.size());
  for (size_t i = 0; i < after.observations.size(); ++i) {
    EXPECT_EQ(from_static.observations[i].facet, after.observations[i].facet);
  }
  std::cout << "update in place: " << after.observations.size()
            << " rays, max distance error " << max_error << " m\n";
  EXPECT_LT(max_error, 1e-5);

  FlatMesh finer;
  AppendGridForTesting(-10, -10, 10, 10, 8, 8, [](double, double) { return 2.0; }, &finer);
  EXPECT_EQ(scene.Update(TessellateFlatForTesting(finer)), SurfaceScene::UpdateKind::kRebuilt);
  EXPECT_EQ(scene.NumBuilds(), 2);
  EXPECT_EQ(scene.NumFaces(), 128);
  const CastResult rebuilt = CastPixels(scene, camera, pose, PixelRect::Full(camera));
  ASSERT_FALSE(rebuilt.observations.empty());
  float nearest = 1e30f;
  for (const PixelObservation& obs : rebuilt.observations) nearest = std::min(nearest, obs.distance);
  EXPECT_NEAR(nearest, 8.0, 0.01);  // plane z = 2 below the camera at z = 10
}

TEST(SurfaceScene, RejectsBadTessellations) {
  FlatMesh mesh;
  AppendGridForTesting(0, 0, 1, 1, 1, 1, [](double, double) { return 0.0; }, &mesh);
  Tessellation tess = TessellateFlatForTesting(mesh);
  Tessellation odd = tess;
  odd.triangles.pop_back();
  EXPECT_THROW(SurfaceScene{odd}, std::invalid_argument);
  Tessellation nan = tess;
  nan.points[3].x() = std::nan("");
  try {
    SurfaceScene scene(nan);
    FAIL() << "NaN point accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("point 3"), std::string::npos) << e.what();
  }
  SurfaceScene scene(tess);
  EXPECT_THROW(scene.Update(nan), std::invalid_argument);
  CastOptions options;
  options.min_cos_incidence = 2;
  EXPECT_THROW(options.Check(), std::invalid_argument);
}

TEST(FlatTessellation, SharesNodesOnEdges) {
  FlatMesh mesh;
  AppendGridForTesting(0, 0, 1, 1, 1, 1, [](double, double) { return 0.0; }, &mesh);
  const Tessellation tess = TessellateFlatForTesting(mesh);
  // V + 3E + 3F = 4 + 3 * 5 + 3 * 2 = 25 = a 5x5 lattice.
  EXPECT_EQ(tess.points.size(), 25u);
  EXPECT_EQ(tess.triangles.size(), 32u);
}

// Acceptance 1: Embree against brute force on a box standing on a plane, seen
// obliquely (the box hides part of the ground).
TEST(CastPixels, MatchesBruteForceOnBoxOnPlane) {
  int num_ground_faces = 0;
  const FlatMesh mesh = GroundWithBox({-2, -2, 0}, {2, 2, 3}, 10, &num_ground_faces);
  const Tessellation tess = TessellateFlatForTesting(mesh);
  const SurfaceScene scene(tess);
  const Camera camera = PinholeCamera(200, 150, 160);
  const Rigid3d pose = LookAt({3, -14, 9}, {0, 0, 1});
  CastOptions options;
  options.keep_invalid = true;
  options.cull_back_faces = false;
  options.min_cos_incidence = 0;
  const CastResult cast = CastPixels(scene, camera, pose, PixelRect::Full(camera), options);
  ASSERT_EQ(cast.observations.size(), 200u * 150u);
  const PixelRays rays(camera, pose);
  const Eigen::Vector3d origin = rays.origin().cast<float>().cast<double>();
  long long compared = 0, near_edge = 0, same = 0, mismatched = 0, hits = 0, box_hits = 0;
  long long hidden_ground = 0;
  double max_relative_distance = 0;
  for (const PixelObservation& obs : cast.observations) {
    const Eigen::Vector3d direction =
        rays.Direction(obs.x, obs.y).cast<float>().cast<double>();
    const BruteHit brute = BruteForce(tess, origin, direction);
    // Near an edge both neighbours (or a silhouette and what lies behind) are right.
    const bool embree_near_edge =
        obs.facet >= 0 && std::min({obs.u, obs.v, 1.0f - obs.u - obs.v}) < 1e-6f;
    if ((brute.facet >= 0 && brute.edge < 1e-6) || embree_near_edge) {
      ++near_edge;
      continue;
    }
    ++compared;
    if (brute.facet != obs.facet) {
      ++mismatched;
      continue;
    }
    ++same;
    if (brute.facet < 0) continue;
    ++hits;
    box_hits += obs.face >= num_ground_faces;
    max_relative_distance =
        std::max(max_relative_distance, std::fabs(obs.distance - brute.t) / brute.t);
    // The ground ray would have reached the ground further away: occlusion seen.
    if (obs.face >= num_ground_faces && direction.z() < 0 &&
        std::fabs(origin.x() + direction.x() * (-origin.z() / direction.z())) < 10 &&
        std::fabs(origin.y() + direction.y() * (-origin.z() / direction.z())) < 10) {
      ++hidden_ground;
    }
  }
  std::cout << "brute force: " << cast.observations.size() << " rays, " << compared
            << " compared, " << near_edge << " within 1e-6 of an edge, " << same
            << " identical (" << hits << " hits, " << box_hits << " on the box, "
            << hidden_ground << " hiding ground), " << mismatched
            << " different; max relative distance error " << max_relative_distance << "\n";
  RecordProperty("mismatched", static_cast<int>(mismatched));
  EXPECT_EQ(mismatched, 0);
  EXPECT_EQ(same, compared);
  EXPECT_LT(max_relative_distance, 1e-4);
  EXPECT_GT(box_hits, 1000);
  EXPECT_GT(hidden_ground, 1000);
  EXPECT_LT(near_edge, compared / 100);
}

// Acceptance 2: a wall hides part of the ground in an oblique view; no pixel is ever
// attributed to the hidden ground.
TEST(CastPixels, OccludedPixelsNeverSeeTheHiddenGround) {
  const Eigen::AlignedBox3d wall(Eigen::Vector3d(-6, -0.25, 0), Eigen::Vector3d(6, 0.25, 4));
  int num_ground_faces = 0;
  const FlatMesh mesh = GroundWithBox(wall.min(), wall.max(), 20, &num_ground_faces);
  const Tessellation tess = TessellateFlatForTesting(mesh);
  const SurfaceScene scene(tess);
  const Camera camera = PinholeCamera(320, 240, 250);
  const Rigid3d pose = LookAt({0, -18, 6}, {0, 4, 0});
  const CastResult cast = CastPixels(scene, camera, pose, PixelRect::Full(camera));
  const PixelRays rays(camera, pose);
  const Eigen::Vector3d origin = rays.origin();
  const double eps = 1e-4;
  const Eigen::AlignedBox3d inner(wall.min().array() + eps, wall.max().array() - eps);
  const Eigen::AlignedBox3d outer(wall.min().array() - eps, wall.max().array() + eps);
  long long occluded = 0, occluded_on_ground = 0, ground = 0, ground_behind_wall = 0;
  for (const PixelObservation& obs : cast.observations) {
    const Eigen::Vector3d direction = rays.Direction(obs.x, obs.y);
    const double t_ground =
        direction.z() < 0 ? -origin.z() / direction.z() : std::numeric_limits<double>::infinity();
    const bool on_ground = obs.face < num_ground_faces;
    if (RayBoxEntry(origin, direction, inner) < t_ground) {
      ++occluded;
      occluded_on_ground += on_ground;
    }
    if (on_ground) {
      ++ground;
      // The segment from the projection centre to the ground point must be free.
      ground_behind_wall += RayBoxEntry(origin, direction, inner) < obs.distance;
    }
  }
  // Ground faces entirely in the wall's shadow (seen from the camera) get no pixel.
  const VisibilityMap map = BuildVisibilityMap(scene, camera, pose);
  const std::vector<int> pixels_per_face = map.PixelsPerFace(scene.NumFaces());
  int hidden_faces = 0, hidden_faces_with_pixels = 0;
  for (int f = 0; f < num_ground_faces; ++f) {
    bool all_hidden = true;
    for (int c = 0; c < 3; ++c) {
      const Eigen::Vector3d& p = mesh.vertices[mesh.faces[f][c]];
      const Eigen::Vector3d d = (p - origin);
      if (!(RayBoxEntry(origin, d.normalized(), outer) < d.norm() - 1e-3)) all_hidden = false;
    }
    if (all_hidden) {
      ++hidden_faces;
      hidden_faces_with_pixels += pixels_per_face[f] > 0;
    }
  }
  std::cout << "occlusion: " << cast.stats.rays << " rays, " << occluded
            << " occluded by the wall (" << occluded_on_ground << " attributed to ground), "
            << ground << " ground observations (" << ground_behind_wall
            << " behind the wall), " << hidden_faces << " ground faces hidden ("
            << hidden_faces_with_pixels << " with pixels)\n";
  EXPECT_GT(occluded, 5000);
  EXPECT_EQ(occluded_on_ground, 0);
  EXPECT_EQ(ground_behind_wall, 0);
  EXPECT_GT(hidden_faces, 10);
  EXPECT_EQ(hidden_faces_with_pixels, 0);
}

// Occluders (the surface around a window) stop rays like the surface itself, but a
// pixel that hits them first is kOccluded: split the wall-on-ground scene into the
// ground (the window) and the wall (occluders) and compare with the whole scene.
TEST(CastPixels, OccludersHideLikeTheWholeSurface) {
  const Eigen::Vector3d wall_min(-6, -0.25, 0), wall_max(6, 0.25, 4);
  int num_ground_faces = 0;
  const FlatMesh whole = GroundWithBox(wall_min, wall_max, 20, &num_ground_faces);
  FlatMesh ground, wall;
  AppendGridForTesting(-10, -10, 10, 10, 20, 20, [](double, double) { return 0.0; }, &ground);
  AppendBoxForTesting(wall_min, wall_max, /*with_bottom=*/false, &wall);
  const Tessellation whole_tess = TessellateFlatForTesting(whole);
  const Tessellation ground_tess = TessellateFlatForTesting(ground);
  const Tessellation wall_tess = TessellateFlatForTesting(wall);
  const SurfaceScene whole_scene(whole_tess);
  SurfaceScene window_scene(ground_tess);
  window_scene.SetOccluders(wall_tess.points, wall_tess.triangles);
  const Camera camera = PinholeCamera(320, 240, 250);
  const Rigid3d pose = LookAt({0, -18, 6}, {0, 4, 0});
  CastOptions options;
  options.keep_invalid = true;
  const CastResult a = CastPixels(whole_scene, camera, pose, PixelRect::Full(camera), options);
  const CastResult b = CastPixels(window_scene, camera, pose, PixelRect::Full(camera), options);
  ASSERT_EQ(a.observations.size(), b.observations.size());
  long long mismatched = 0, on_wall = 0;
  for (size_t i = 0; i < a.observations.size(); ++i) {
    const PixelObservation& pa = a.observations[i];
    const PixelObservation& pb = b.observations[i];
    ASSERT_EQ(pa.x, pb.x);
    ASSERT_EQ(pa.y, pb.y);
    const bool wall_hit = pa.status != RayStatus::kMiss && pa.face >= num_ground_faces;
    on_wall += wall_hit;
    if (wall_hit) {
      mismatched += pb.status != RayStatus::kOccluded;
    } else {
      mismatched += pb.status != pa.status || (pa.valid() && pa.face != pb.face);
    }
  }
  std::cout << "occluders: " << on_wall << " pixels on the wall, " << b.stats.occluded
            << " occluded, " << mismatched << " pixels differ\n";
  EXPECT_GT(on_wall, 5000);
  EXPECT_EQ(b.stats.occluded, on_wall - mismatched);
  EXPECT_LE(mismatched, 10);  // ties on the wall's foot line may go either way
}

// Pixels whose status, face or facet barycentrics differ between two casts of the same
// pixels (in the same order).
long long PixelsThatDiffer(const CastResult& a, const CastResult& b) {
  long long differ = 0;
  for (size_t i = 0; i < a.observations.size() && i < b.observations.size(); ++i) {
    const PixelObservation& pa = a.observations[i];
    const PixelObservation& pb = b.observations[i];
    differ += pa.status != pb.status || pa.face != pb.face || pa.u != pb.u || pa.v != pb.v;
  }
  return differ;
}

// One occluder scene instanced by two surface scenes (a window's runs) casts every pixel
// as occluders built for the scene alone do; occluders can be replaced.
TEST(CastPixels, SharedOccluderSceneCastsLikeItsOwn) {
  const Eigen::Vector3d wall_min(-6, -0.25, 0), wall_max(6, 0.25, 4);
  FlatMesh ground, wall;
  AppendGridForTesting(-10, -10, 10, 10, 20, 20, [](double, double) { return 0.0; }, &ground);
  AppendBoxForTesting(wall_min, wall_max, /*with_bottom=*/false, &wall);
  const Tessellation ground_tess = TessellateFlatForTesting(ground);
  const Tessellation wall_tess = TessellateFlatForTesting(wall);
  SurfaceScene own(ground_tess);
  own.SetOccluders(wall_tess.points, wall_tess.triangles);
  const auto shared = std::make_shared<const OccluderScene>(EmbreeDevice::Shared(), wall_tess.points,
                                                            wall_tess.triangles);
  SurfaceScene first(ground_tess), second(ground_tess);
  first.SetOccluders(shared);
  second.SetOccluders(shared);
  EXPECT_EQ(first.NumBuilds(), 1);  // the surface's BVH is not built again
  const Camera camera = PinholeCamera(320, 240, 250);
  const Rigid3d pose = LookAt({0, -18, 6}, {0, 4, 0});
  CastOptions options;
  options.keep_invalid = true;
  const CastResult a = CastPixels(own, camera, pose, PixelRect::Full(camera), options);
  EXPECT_GT(a.stats.occluded, 5000);
  for (const SurfaceScene* scene : {&first, &second}) {
    const CastResult b = CastPixels(*scene, camera, pose, PixelRect::Full(camera), options);
    ASSERT_EQ(a.observations.size(), b.observations.size());
    EXPECT_EQ(PixelsThatDiffer(a, b), 0);
    EXPECT_EQ(b.stats.occluded, a.stats.occluded);
  }
  // Replaced (a window that moved out of the region its occluders were selected for): a
  // wall behind the ground hides less, none hides nothing, the wall again casts as before,
  // and the surface's BVH is never rebuilt.
  FlatMesh far_wall;
  AppendBoxForTesting({-6, 20, 0}, {6, 21, 4}, /*with_bottom=*/false, &far_wall);
  const Tessellation far_tess = TessellateFlatForTesting(far_wall);
  first.SetOccluders(far_tess.points, far_tess.triangles);
  EXPECT_LT(CastPixels(first, camera, pose, PixelRect::Full(camera), options).stats.occluded, a.stats.occluded);
  first.SetOccluders(nullptr);
  EXPECT_EQ(CastPixels(first, camera, pose, PixelRect::Full(camera), options).stats.occluded, 0);
  first.SetOccluders(shared);
  EXPECT_EQ(PixelsThatDiffer(a, CastPixels(first, camera, pose, PixelRect::Full(camera), options)), 0);
  EXPECT_EQ(first.NumBuilds(), 1);
}

// Rays honour lens distortion: the hit point, rebuilt from face barycentrics,
// projects back onto the pixel centre.
TEST(CastPixels, HitPointsReprojectThroughDistortion) {
  FlatMesh mesh;
  AppendGridForTesting(-20, -20, 20, 20, 8, 8,
                       [](double x, double y) { return 0.05 * x - 0.03 * y; }, &mesh);
  const Tessellation tess = TessellateFlatForTesting(mesh);
  const SurfaceScene scene(tess);
  Camera camera = Camera::Create(CameraModel::kOpenCV, 300, 305, 161, 119, 320, 240);
  camera.params[4] = -0.12;  // k1
  camera.params[5] = 0.03;   // k2
  camera.params[6] = 1e-3;   // p1
  camera.params[7] = -5e-4;  // p2
  const Rigid3d pose = LookAt({2, -9, 12}, {0, 1, 0});
  const CastResult cast = CastPixels(scene, camera, pose, PixelRect::Full(camera));
  const PixelRays rays(camera, pose);
  double max_pixel_error = 0, max_distance_error = 0;
  for (const PixelObservation& obs : cast.observations) {
    const Eigen::Vector3i& f = mesh.faces[obs.face];
    const Eigen::Vector3d b = obs.FaceBarycentrics();
    const Eigen::Vector3d point =
        b[0] * mesh.vertices[f[0]] + b[1] * mesh.vertices[f[1]] + b[2] * mesh.vertices[f[2]];
    const Eigen::Vector2d pixel = camera.ImageFromCam(pose * point);
    max_pixel_error = std::max(
        max_pixel_error, (pixel - Eigen::Vector2d(obs.x + 0.5, obs.y + 0.5)).norm());
    max_distance_error = std::max(
        max_distance_error, std::fabs((point - rays.origin()).norm() - obs.distance) /
                                obs.distance);
  }
  std::cout << "distortion: " << cast.observations.size()
            << " observations, max reprojection error " << max_pixel_error
            << " px, max relative distance error " << max_distance_error << "\n";
  EXPECT_EQ(cast.stats.observations, 320 * 240);
  EXPECT_LT(max_pixel_error, 0.01);
  EXPECT_LT(max_distance_error, 1e-5);
}

// Facet normals follow the counter-clockwise orientation: seen from below, a
// ground plane with upward normals is all back face.
TEST(CastPixels, BackFacesAndIncidence) {
  FlatMesh mesh;
  AppendGridForTesting(-20, -20, 20, 20, 4, 4, [](double, double) { return 0.0; }, &mesh);
  const SurfaceScene scene(TessellateFlatForTesting(mesh));
  const Camera camera = PinholeCamera(100, 80, 90);
  const Rigid3d above = LookAt({0, -3, 2}, {0, 4, 0});
  const Rigid3d below = LookAt({0, -3, -2}, {0, 4, 0});
  const CastResult front = CastPixels(scene, camera, above, PixelRect::Full(camera));
  const CastResult back = CastPixels(scene, camera, below, PixelRect::Full(camera));
  CastOptions no_culling;
  no_culling.cull_back_faces = false;
  const CastResult back_kept =
      CastPixels(scene, camera, below, PixelRect::Full(camera), no_culling);
  // Incidence: the plane normal is +z, so cos = |d_z|.
  const PixelRays rays(camera, above);
  double max_cos_error = 0;
  for (const PixelObservation& obs : front.observations) {
    max_cos_error = std::max(max_cos_error, std::fabs(obs.cos_incidence -
                                                      std::fabs(rays.Direction(obs.x, obs.y).z())));
    EXPECT_GE(obs.cos_incidence, 0.1f);
  }
  std::cout << "orientation: front " << front.stats.observations << " obs, "
            << front.stats.grazing << " grazing; back " << back.stats.back_faces
            << " back faces, " << back.stats.observations << " obs; without culling "
            << back_kept.stats.observations << " obs; max cos error " << max_cos_error << "\n";
  EXPECT_GT(front.stats.observations, 4000);
  EXPECT_GT(front.stats.grazing, 0);  // the far ground is seen at grazing incidence
  EXPECT_EQ(front.stats.back_faces, 0);
  EXPECT_EQ(back.stats.observations, 0);
  EXPECT_EQ(back.stats.back_faces, front.stats.observations + front.stats.grazing);
  EXPECT_EQ(back_kept.stats.observations, front.stats.observations);
  EXPECT_LT(max_cos_error, 1e-5);
  EXPECT_EQ(front.stats.rays, front.stats.observations + front.stats.grazing +
                                  front.stats.back_faces + front.stats.misses);
}

// Pixel lists, rectangles and thread counts give the same observations.
TEST(CastPixels, ListRectangleAndThreadCountAgree) {
  int num_ground_faces = 0;
  const FlatMesh mesh = GroundWithBox({-2, -2, 0}, {2, 2, 3}, 10, &num_ground_faces);
  const SurfaceScene scene(TessellateFlatForTesting(mesh));
  const Camera camera = PinholeCamera(150, 100, 120);
  const Rigid3d pose = LookAt({3, -14, 9}, {0, 0, 1});
  const PixelRect rect{17, 9, 131, 77};
  CastOptions options;
  options.keep_invalid = true;
  const CastResult parallel = CastPixels(scene, camera, pose, rect, options);
  CastResult serial;
  {
    tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);
    serial = CastPixels(scene, camera, pose, rect, options);
  }
  std::vector<Eigen::Vector2i> pixels;
  for (const PixelObservation& obs : parallel.observations) pixels.emplace_back(obs.x, obs.y);
  pixels.emplace_back(-1, 5);  // outside: skipped
  const CastResult listed = CastPixels(scene, camera, pose, pixels, options);
  ASSERT_EQ(parallel.observations.size(), static_cast<size_t>(rect.Area()));
  ASSERT_EQ(serial.observations.size(), parallel.observations.size());
  ASSERT_EQ(listed.observations.size(), parallel.observations.size());
  long long differences = 0;
  for (size_t i = 0; i < parallel.observations.size(); ++i) {
    const PixelObservation &a = parallel.observations[i], &b = serial.observations[i],
                           &c = listed.observations[i];
    differences += a.x != b.x || a.y != b.y || a.facet != b.facet || a.distance != b.distance;
    differences += a.x != c.x || a.y != c.y || a.facet != c.facet || a.status != c.status ||
                   std::fabs(a.distance - c.distance) > 1e-5f * a.distance;
  }
  std::cout << "list/rect/threads: " << parallel.observations.size() << " pixels, "
            << differences << " differences\n";
  EXPECT_EQ(differences, 0);
  // Valid-only output holds exactly the valid entries.
  const CastResult valid_only = CastPixels(scene, camera, pose, rect);
  EXPECT_EQ(static_cast<long long>(valid_only.observations.size()),
            parallel.stats.observations);
}

TEST(ImageSelection, ProjectedBoxCoversTheWindowsPixels) {
  int num_ground_faces = 0;
  const FlatMesh mesh = GroundWithBox({-2, -2, 0}, {2, 2, 3}, 10, &num_ground_faces);
  const Tessellation tess = TessellateFlatForTesting(mesh);
  const SurfaceScene scene(tess);
  ImageBlock block;
  block.cameras[1] = PinholeCamera(200, 150, 160);
  block.cameras[1].camera_id = 1;
  Camera distorted = Camera::Create(CameraModel::kRadial, 160, 160, 100, 75, 200, 150);
  distorted.camera_id = 2;
  distorted.params[3] = -0.15;
  distorted.params[4] = 0.02;
  block.cameras[2] = distorted;
  auto add = [&](int id, int camera_id, const Rigid3d& pose) {
    BlockImage image;
    image.image_id = id;
    image.camera_id = camera_id;
    image.cam_from_world = pose;
    block.images.push_back(image);
  };
  add(10, 1, LookAt({3, -14, 9}, {0, 0, 1}));     // sees the box
  add(11, 1, LookAt({3, -14, 9}, {0, -30, 1}));   // box behind the camera
  add(12, 1, LookAt({30, -20, 9}, {30, 30, 0}));  // box in front, beside the view
  add(13, 2, LookAt({-9, 9, 8}, {-1, 0, 0}));     // distorted, sees the box
  std::vector<int> window;
  for (int f = num_ground_faces; f < tess.NumFaces(); ++f) window.push_back(f);
  const Eigen::AlignedBox3d box = FacesBoundingBox(tess, window);
  EXPECT_NEAR(box.max().z(), 3.0, 1e-12);
  const std::vector<ImageSelection> selection = SelectImages(box, block);
  ASSERT_EQ(selection.size(), 2u);
  EXPECT_EQ(selection[0].image_id, 10);
  EXPECT_EQ(selection[1].image_id, 13);
  const std::vector<ImageCast> window_casts = CastWindow(scene, block, box);
  ASSERT_EQ(window_casts.size(), 2u);
  EXPECT_EQ(window_casts[1].cast.stats.rays, selection[1].rect.Area());
  for (const ImageSelection& selected : selection) {
    const BlockImage& image = block.images[selected.image_index];
    const CastResult all = CastPixels(scene, block, selected.image_index,
                                      PixelRect::Full(block.CameraOf(image)));
    PixelRect hull{1 << 30, 1 << 30, -1, -1};
    long long outside = 0, window_pixels = 0;
    for (const PixelObservation& obs : all.observations) {
      if (obs.face < num_ground_faces) continue;
      ++window_pixels;
      outside += !selected.rect.Contains(obs.x, obs.y);
      hull = {std::min(hull.x0, obs.x), std::min(hull.y0, obs.y), std::max(hull.x1, obs.x + 1),
              std::max(hull.y1, obs.y + 1)};
    }
    std::cout << "image " << selected.image_id << ": rect [" << selected.rect.x0 << ", "
              << selected.rect.x1 << ") x [" << selected.rect.y0 << ", " << selected.rect.y1
              << "), window pixels " << window_pixels << " in [" << hull.x0 << ", " << hull.x1
              << ") x [" << hull.y0 << ", " << hull.y1 << "), outside " << outside << "\n";
    EXPECT_GT(window_pixels, 1000);
    EXPECT_EQ(outside, 0);
    // Tight: no more than margin + 2 pixels of slack on any side.
    EXPECT_LE(hull.x0 - selected.rect.x0, 4);
    EXPECT_LE(selected.rect.x1 - hull.x1, 4);
    EXPECT_LE(hull.y0 - selected.rect.y0, 4);
    EXPECT_LE(selected.rect.y1 - hull.y1, 4);
  }
}

TEST(FaceBvh, FacesInBoxMatchesBruteForce) {
  FlatMesh mesh;
  AppendGridForTesting(-10, -10, 10, 10, 30, 30,
                       [](double x, double y) { return std::sin(0.3 * x) * std::cos(0.2 * y); },
                       &mesh);
  AppendBoxForTesting({-2, -3, 0}, {1, 2, 4}, false, &mesh);
  const Tessellation tess = TessellateFlatForTesting(mesh);
  const FaceBvh bvh(tess);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> coord(-12, 12), size(0.1, 6);
  long long total = 0;
  int mismatches = 0;
  for (int q = 0; q < 200; ++q) {
    const Eigen::Vector3d lo(coord(rng), coord(rng), coord(rng) / 4);
    const Eigen::AlignedBox3d box(lo, lo + Eigen::Vector3d(size(rng), size(rng), size(rng)));
    std::vector<int> expected;
    for (int f = 0; f < tess.NumFaces(); ++f) {
      if (FacesBoundingBox(tess, {f}).intersects(box)) expected.push_back(f);
    }
    const std::vector<int> found = bvh.FacesInBox(box);
    mismatches += found != expected;
    total += found.size();
  }
  std::cout << "bvh: 200 queries, " << total << " faces found, " << mismatches
            << " mismatches\n";
  EXPECT_EQ(mismatches, 0);
  EXPECT_GT(total, 1000);
}

TEST(VisibilityMap, CountsImagesPerFaceVertexAndNode) {
  int num_ground_faces = 0;
  const FlatMesh mesh = GroundWithBox({-2.5, -2.5, 0}, {2.5, 2.5, 3}, 10, &num_ground_faces);
  const Tessellation tess = TessellateFlatForTesting(mesh);
  const SurfaceScene scene(tess);
  const Camera camera = PinholeCamera(200, 150, 140);
  // The footprint [-2.5, 2.5]^2 strictly contains ground cells (4..5, 4..5).
  std::vector<VisibilityMap> maps;
  for (const Eigen::Vector3d& centre :
       {Eigen::Vector3d(0, -14, 9), Eigen::Vector3d(14, 0, 9), Eigen::Vector3d(0, 14, 9),
        Eigen::Vector3d(-14, 0, 9)}) {
    maps.push_back(BuildVisibilityMap(scene, camera, LookAt(centre, {0, 0, 1})));
  }
  const std::vector<int> per_face = CountImagesPerFace(maps, scene.NumFaces());
  // Box faces: 0-1 top, then front (-y), right (+x), back (+y), left (-x).
  const int top = num_ground_faces;
  EXPECT_EQ(per_face[top], 4);
  EXPECT_EQ(per_face[top + 1], 4);
  for (int side = 0; side < 4; ++side) {
    EXPECT_EQ(per_face[top + 2 + 2 * side], 1) << "side " << side;
  }
  // Ground faces under the box (grid cells (4..5, 4..5) of the 10x10 grid) are unseen.
  int under_box_seen = 0;
  for (int j = 4; j <= 5; ++j) {
    for (int i = 4; i <= 5; ++i) {
      under_box_seen += per_face[2 * (j * 10 + i)] + per_face[2 * (j * 10 + i) + 1];
    }
  }
  EXPECT_EQ(under_box_seen, 0);
  const std::vector<int> per_vertex =
      CountImagesPerVertex(maps, mesh.faces, static_cast<int>(mesh.vertices.size()));
  const int box_top_vertex = static_cast<int>(mesh.vertices.size()) - 1;  // (2.5, 2.5, 3)
  EXPECT_EQ(per_vertex[box_top_vertex], 4);
  const std::vector<int> per_node = CountImagesPerNode(maps, tess);
  // The ground node at the box's centre (interior of the footprint) is unseen.
  int centre_node = -1;
  for (int n = 0; n < static_cast<int>(tess.points.size()); ++n) {
    if (tess.points[n].norm() < 1e-12) centre_node = n;
  }
  ASSERT_GE(centre_node, 0);
  EXPECT_EQ(per_node[centre_node], 0);
  int seen_by_two = 0;
  for (int count : per_face) seen_by_two += count >= 2;
  std::cout << "visibility maps: " << scene.NumFaces() << " faces, " << seen_by_two
            << " seen by >= 2 images; top face " << per_face[top] << " images\n";
}

}  // namespace
}  // namespace facets
