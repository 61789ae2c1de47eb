#include "engine/start/visual_hull.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "mesh/closed_surface.h"
#include "visibility/embree_scene.h"

namespace facets {
namespace {

// A camera at `centre` looking at the origin (COLMAP frame: x right, y down, z ahead).
Rigid3d LookAtOrigin(const Eigen::Vector3d& centre) {
  const Eigen::Vector3d z = (-centre).normalized();
  Eigen::Vector3d up = std::abs(z.z()) > 0.9 ? Eigen::Vector3d::UnitY() : Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d x = z.cross(up).normalized();
  const Eigen::Vector3d y = z.cross(x);
  Eigen::Matrix3d r;
  r.row(0) = x;
  r.row(1) = y;
  r.row(2) = z;
  return Rigid3d(Eigen::Quaterniond(r), -(r * centre));
}

// Ten cameras around an ellipsoid (radii 0.12, 0.1, 0.08 m) at 1 m: eight on a ring
// 20 degrees above its equator, two looking down steeply; masks = its coverage.
TEST(VisualHull, EllipsoidIsCarvedFromTenSilhouettesAndMeshedClosed) {
  Ellipsoid e;
  e.radii = Eigen::Vector3d(0.12, 0.1, 0.08);
  std::vector<Eigen::Vector3d> truth_points;
  std::vector<Eigen::Vector3i> truth_triangles;
  TinPointsAndTriangles(MakeEllipsoidMesh(e, 0.005), &truth_points, &truth_triangles);
  const TriangleScene truth(EmbreeDevice::Shared(), truth_points, truth_triangles);
  const Camera camera = Camera::Create(CameraModel::kPinhole, 300, 300, 100, 100, 200, 200);
  std::vector<Camera> cameras;
  std::vector<Rigid3d> poses;
  std::vector<PixelMask> masks;
  for (int k = 0; k < 10; ++k) {
    const double azimuth = 2.0 * M_PI * k / (k < 8 ? 8.0 : 2.0) + 0.3;
    const double elevation = (k < 8 ? 20.0 : 70.0) * M_PI / 180.0;
    const Eigen::Vector3d c(std::cos(elevation) * std::cos(azimuth),
                            std::cos(elevation) * std::sin(azimuth), std::sin(elevation));
    cameras.push_back(camera);
    poses.push_back(LookAtOrigin(c));
    masks.push_back(CoverageMask(truth, camera, poses.back()));
  }
  VisualHullOptions options;
  options.voxel_size = 0.003;
  const Eigen::AlignedBox3d box(Eigen::Vector3d::Constant(-0.2), Eigen::Vector3d::Constant(0.2));
  const VisualHullGrid grid = CarveVisualHull(cameras, poses, masks, box, options);
  const double truth_volume = 4.0 / 3.0 * M_PI * 0.12 * 0.1 * 0.08;
  // The visual hull holds the object; ten views leave a little more around it.
  EXPECT_GT(grid.Volume(), 0.97 * truth_volume);
  EXPECT_LT(grid.Volume(), 1.25 * truth_volume);

  std::vector<Eigen::Vector3d> points;
  std::vector<Eigen::Vector3i> triangles;
  MeshVisualHull(grid, 0.02, &points, &triangles);
  const ClosedSurfaceCheck check = CheckClosedSurface(points, triangles);
  EXPECT_TRUE(check.closed);
  EXPECT_FALSE(check.self_intersecting);
  EXPECT_GT(check.volume, 0.9 * truth_volume);  // normals point out
  EXPECT_LT(check.volume, 1.25 * truth_volume);
  const TriangleScene hull(EmbreeDevice::Shared(), points, triangles);
  double min_iou = 1.0;
  for (size_t k = 0; k < cameras.size(); ++k) {
    min_iou = std::min(min_iou, CompareMasks(masks[k], CoverageMask(hull, cameras[k], poses[k])).IoU());
  }
  EXPECT_GT(min_iou, 0.93);
  std::printf("visual hull: %lld voxels, volume %.5f (truth %.5f), mesh %zu vertices %zu triangles, "
              "volume %.5f, min IoU %.4f\n",
              grid.Count(), grid.Volume(), truth_volume, points.size(), triangles.size(),
              check.volume, min_iou);
}

TEST(VisualHull, PointsOutsideArePulledInAlongTheirDirection) {
  VisualHullGrid grid;
  grid.voxel = 0.004;
  grid.size = Eigen::Vector3i::Constant(100);
  grid.origin = Eigen::Vector3d::Constant(-0.198);
  grid.inside.assign(100 * 100 * 100, 0);
  for (int k = 0; k < 100; ++k) {
    for (int j = 0; j < 100; ++j) {
      for (int i = 0; i < 100; ++i) grid.inside[grid.Index(i, j, k)] = grid.Centre(i, j, k).norm() < 0.1;
    }
  }
  const HullOccupancy occupancy = SmoothHullOccupancy(grid);
  std::vector<Eigen::Vector3d> points, directions;
  for (int n = 0; n < 50; ++n) {
    const Eigen::Vector3d u = Eigen::Vector3d(std::cos(n), std::sin(n), 0.02 * n - 0.5).normalized();
    points.push_back((n < 40 ? 0.13 : n < 45 ? 0.08 : 0.2) * u);  // outside, inside, far out
    directions.push_back(u);
  }
  const std::vector<Eigen::Vector3d> before = points;
  int unresolved = 0;
  EXPECT_EQ(PullInsideHull(occupancy, directions, 0.05, &points, &unresolved), 40);
  EXPECT_EQ(unresolved, 5);
  for (int n = 0; n < 40; ++n) {
    EXPECT_TRUE(occupancy.Inside(points[n]));
    EXPECT_NEAR(points[n].norm(), 0.1, 0.5 * grid.voxel) << n;
  }
  for (int n = 40; n < 50; ++n) EXPECT_EQ(points[n], before[n]);
}

// A sphere of 0.1 m carved from eight views on a ring 20 degrees above its equator;
// points shrunk to 0.085 m along their radial direction. Those an image sees edge-on
// (the rim circles of the eight views) are pushed back out onto the hull; the others,
// points deep inside and points outside stay.
TEST(VisualHull, PointsOnTheRimsArePushedOutOntoTheHull) {
  Ellipsoid e;
  e.radii = Eigen::Vector3d::Constant(0.1);
  std::vector<Eigen::Vector3d> truth_points;
  std::vector<Eigen::Vector3i> truth_triangles;
  TinPointsAndTriangles(MakeEllipsoidMesh(e, 0.004), &truth_points, &truth_triangles);
  const TriangleScene truth(EmbreeDevice::Shared(), truth_points, truth_triangles);
  const Camera camera = Camera::Create(CameraModel::kPinhole, 600, 600, 200, 200, 400, 400);
  HullViews views;
  std::vector<Eigen::Vector3d> centres;
  for (int k = 0; k < 8; ++k) {
    const double azimuth = 2.0 * M_PI * k / 8.0, elevation = 20.0 * M_PI / 180.0;
    centres.emplace_back(std::cos(elevation) * std::cos(azimuth), std::cos(elevation) * std::sin(azimuth),
                         std::sin(elevation));
    views.cameras.push_back(camera);
    views.cam_from_world.push_back(LookAtOrigin(centres.back()));
    views.masks.push_back(CoverageMask(truth, camera, views.cam_from_world.back()));
  }
  VisualHullOptions options;
  options.voxel_size = 0.002;
  const Eigen::AlignedBox3d box(Eigen::Vector3d::Constant(-0.15), Eigen::Vector3d::Constant(0.15));
  const VisualHullGrid grid = CarveVisualHull(views.cameras, views.cam_from_world, views.masks, box, options);
  const HullOccupancy occupancy = SmoothHullOccupancy(grid);

  const double max_cos = 0.1;
  std::vector<Eigen::Vector3d> points, directions;
  std::vector<bool> rim;
  for (int n = 0; n < 400; ++n) {  // a spiral over the sphere
    const double z = -0.95 + 1.9 * n / 399.0, phi = 2.4 * n;
    const Eigen::Vector3d u(std::sqrt(1 - z * z) * std::cos(phi), std::sqrt(1 - z * z) * std::sin(phi), z);
    double edge_on = 1.0;
    for (const Eigen::Vector3d& c : centres) edge_on = std::min(edge_on, std::abs((0.1 * u - c).normalized().dot(u)));
    points.push_back(0.085 * u);
    directions.push_back(u);
    rim.push_back(edge_on <= max_cos);
  }
  points.push_back(Eigen::Vector3d(0.02, 0.0, 0.0));  // deep inside: no boundary within reach
  directions.push_back(Eigen::Vector3d::UnitX());
  points.push_back(Eigen::Vector3d(0.0, 0.13, 0.0));  // outside: PullInsideHull's business
  directions.push_back(Eigen::Vector3d::UnitY());
  const std::vector<Eigen::Vector3d> before = points;
  const int moved = PushOntoHullRims(occupancy, views, directions, 0.03, max_cos, &points);
  int rims = 0, pushed_rims = 0, pushed_others = 0;
  double worst_inside = 0.0, worst_outside = 0.0;
  for (size_t n = 0; n < rim.size(); ++n) {
    const bool pushed = points[n] != before[n];
    rims += rim[n] ? 1 : 0;
    pushed_rims += rim[n] && pushed ? 1 : 0;
    pushed_others += !rim[n] && pushed ? 1 : 0;
    if (pushed) {
      EXPECT_TRUE(occupancy.Inside(points[n])) << n;
      worst_inside = std::max(worst_inside, 0.1 - points[n].norm());
      worst_outside = std::max(worst_outside, points[n].norm() - 0.1);
    }
  }
  EXPECT_EQ(points[400], before[400]);
  EXPECT_EQ(points[401], before[401]);
  std::printf("rim push: %d of 400 points on a rim (|cos| <= %.2f), %d of them and %d others pushed "
              "(%d in all); pushed points %.4f m inside to %.4f m outside the sphere\n",
              rims, max_cos, pushed_rims, pushed_others, moved, worst_inside, worst_outside);
  EXPECT_GT(rims, 40);
  EXPECT_EQ(moved, pushed_rims + pushed_others);
  EXPECT_GE(pushed_rims, rims * 9 / 10);
  // A point near the rim but just beyond the band is pushed too when the view's ray at the
  // hull's boundary (farther out than the point) is still edge-on; never many.
  EXPECT_LE(pushed_others, rims / 4);
  EXPECT_LE(worst_inside, grid.voxel);
  EXPECT_LE(worst_outside, 3.0 * grid.voxel);
}

TEST(VisualHull, EmptySilhouettesGiveAClearError) {
  const Camera camera = Camera::Create(CameraModel::kPinhole, 300, 300, 100, 100, 200, 200);
  const std::vector<PixelMask> masks(2, PixelMask(200, 200));
  const VisualHullGrid grid = CarveVisualHull(
      {camera, camera}, {LookAtOrigin({1, 0, 0}), LookAtOrigin({0, 1, 0})}, masks,
      Eigen::AlignedBox3d(Eigen::Vector3d::Constant(-0.1), Eigen::Vector3d::Constant(0.1)),
      VisualHullOptions());
  EXPECT_EQ(grid.Count(), 0);
  std::vector<Eigen::Vector3d> points;
  std::vector<Eigen::Vector3i> triangles;
  EXPECT_THROW(MeshVisualHull(grid, 0.02, &points, &triangles), std::runtime_error);
}

// Five images of one pinhole camera (focal 1024 px) at 1, 2, 2, 3 and 9 m from the
// origin: the median footprint at the origin is 2 m / 1024 px = 1/512 m.
ImageBlock FiveImagesAroundTheOrigin() {
  ImageBlock block;
  block.cameras[1] = Camera::Create(CameraModel::kPinhole, 1024, 1024, 512, 384, 1024, 768);
  const Eigen::Vector3d centres[5] = {{1, 0, 0}, {0, 2, 0}, {-2, 0, 0}, {0, -3, 0}, {0, 0, 9}};
  for (int i = 0; i < 5; ++i) {
    BlockImage image;
    image.image_id = i + 1;
    image.camera_id = 1;
    image.cam_from_world = Rigid3d(Eigen::Quaterniond::Identity(), -centres[i]);
    block.images.push_back(image);
  }
  return block;
}

TEST(VisualHull, ConstraintVoxelIsOnePixelFootprintAtTheBoxCentre) {
  const ImageBlock block = FiveImagesAroundTheOrigin();
  const Eigen::AlignedBox3d box(Eigen::Vector3d(-0.125, -0.25, -0.5), Eigen::Vector3d(0.125, 0.25, 0.5));
  // The start's hull: 1 m / 200 = 5 mm voxels.
  const ConstraintVoxelChoice choice = ChooseConstraintVoxel(block, box, 0.0, 0.005);
  EXPECT_EQ(choice.footprint, 1.0 / 512);
  EXPECT_EQ(choice.voxel, 1.0 / 512);
  EXPECT_EQ(choice.voxels, 128LL * 256 * 512);
  EXPECT_NE(choice.why.find("128 x 256 x 512 = 16777216 voxels"), std::string::npos) << choice.why;

  // A hand-set voxel wins, even a coarser one than the start's.
  EXPECT_EQ(ChooseConstraintVoxel(block, box, 0.01, 0.005).voxel, 0.01);
  // A footprint not finer than the start's voxels: no second hull.
  const ConstraintVoxelChoice coarse = ChooseConstraintVoxel(block, box, 0.0, 1.0 / 512);
  EXPECT_EQ(coarse.voxel, 0.0);
  EXPECT_EQ(coarse.voxels, 0);
  EXPECT_NE(coarse.why.find("the start's hull"), std::string::npos) << coarse.why;
}

TEST(VisualHull, ConstraintVoxelCountIsCapped) {
  const ImageBlock block = FiveImagesAroundTheOrigin();
  // A 1 m cube would need 512^3 = 134 million voxels of one footprint.
  const Eigen::AlignedBox3d box(Eigen::Vector3d(-0.5, -0.5, -0.5), Eigen::Vector3d(0.5, 0.5, 0.5));
  const ConstraintVoxelChoice choice = ChooseConstraintVoxel(block, box, 0.0, 0.005);
  EXPECT_LE(choice.voxels, kMaxConstraintVoxels);
  EXPECT_GT(choice.voxels, kMaxConstraintVoxels * 99 / 100);
  EXPECT_GE(choice.voxel, 1.0 / 400);  // 400^3 = 64 million
  EXPECT_LT(choice.voxel, 1.002 / 400);
  EXPECT_NE(choice.why.find("needs more than 64000000 voxels"), std::string::npos) << choice.why;
}

}  // namespace
}  // namespace facets
