// The start surface fitted to tie points: exact for a plane, within a bound of a
// smooth terrain when 10% of the points are gross outliers, holes from the plane.
#include "engine/start/start_tiepoints.h"

#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <random>

namespace facets {
namespace {

double Terrain(double x, double y) {
  return 5.0 + 0.1 * x - 0.05 * y + 2.0 * std::sin(2 * M_PI * x / 60.0) * std::cos(2 * M_PI * y / 70.0);
}

RegionOfInterest Region() {
  RegionOfInterest roi;
  roi.min = Eigen::Vector3d(-40, -35, -60);
  roi.max = Eigen::Vector3d(40, 35, 60);
  return roi;
}

// `count` points on the terrain with 3 cm noise; every tenth a blunder of 4-30 m up or
// down (mismatches, points on trees and cars).
std::vector<Eigen::Vector3d> Points(int count, unsigned seed, bool hole = false) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> ux(-40, 40), uy(-35, 35), blunder(4, 30);
  std::normal_distribution<double> noise(0, 0.03);
  std::vector<Eigen::Vector3d> points;
  while (static_cast<int>(points.size()) < count) {
    const double x = ux(rng), y = uy(rng);
    if (hole && std::hypot(x - 15, y - 5) < 22) continue;
    double z = Terrain(x, y) + noise(rng);
    if (points.size() % 10 == 9) z += (points.size() % 20 == 19 ? -1 : 1) * blunder(rng);
    points.emplace_back(x, y, z);
  }
  return points;
}

struct Errors {
  double rms = 0, max = 0;
};
Errors Compare(const TiePointHeightGrid& grid) {
  Errors e;
  double sum = 0;
  for (int j = 0; j <= grid.ny; ++j) {
    for (int i = 0; i <= grid.nx; ++i) {
      const double x = grid.min.x() + (grid.max.x() - grid.min.x()) * i / grid.nx;
      const double y = grid.min.y() + (grid.max.y() - grid.min.y()) * j / grid.ny;
      const double d = grid.At(x, y) - Terrain(x, y);
      sum += d * d;
      e.max = std::max(e.max, std::abs(d));
    }
  }
  e.rms = std::sqrt(sum / grid.heights.size());
  return e;
}

TEST(StartTiePoints, TenPercentBlundersStayOutOfTheSurface) {
  const std::vector<Eigen::Vector3d> points = Points(400, 7);
  TiePointStartReport report;
  const TiePointHeightGrid grid = FitTiePointHeights(points, Region(), 4.0, {}, &report);
  const Errors e = Compare(grid);
  // The mean of all points (what a non-robust plane would give) for comparison.
  double mean_error = 0;
  for (const auto& p : points) mean_error += p.z() - Terrain(p.x(), p.y());
  mean_error /= points.size();
  std::cout << report.Brief() << "\nfitted vs terrain: rms " << e.rms << " m, max " << e.max
            << " m; mean blunder-laden offset " << mean_error << " m\n";
  EXPECT_EQ(report.points_in_region, 400);
  EXPECT_EQ(report.nodes, 21 * 19);
  EXPECT_GT(report.nodes_from_points, report.nodes * 9 / 10);
  // Blunders are 10% of the points, 4-30 m (in one spot 4 of the 8 nearest points): none
  // may pull the surface by metres. What remains is the 2 m / 60 m terrain wave seen
  // through 4 m nodes and 0.5 m consensus (the median of the neighbours instead of the
  // consensus plane gave rms 0.45 m, max 2.1 m).
  EXPECT_LT(e.rms, 0.25);
  EXPECT_LT(e.max, 1.0);
  // The plane sees the 0.1 / -0.05 tilt despite the blunders.
  EXPECT_NEAR(report.plane[1], 0.1, 0.02);
  EXPECT_NEAR(report.plane[2], -0.05, 0.02);
}

TEST(StartTiePoints, HoleTakesTheRobustPlane) {
  TiePointStartReport report;
  const TiePointHeightGrid grid = FitTiePointHeights(Points(400, 11, /*hole=*/true), Region(), 4.0, {}, &report);
  EXPECT_EQ(report.nodes_from_plane + report.nodes_from_points, report.nodes);
  // Radius 22 m hole, neighbourhoods up to 16 m: the nodes near its centre see no points.
  EXPECT_GT(report.nodes_from_plane, 0);
  // In the hole the plane differs from the terrain by about its 2 m wave (+ smoothing).
  EXPECT_LT(Compare(grid).max, 3.0);
}

TEST(StartTiePoints, ExactPlaneIsReproduced) {
  std::vector<Eigen::Vector3d> points;
  for (int k = 0; k < 100; ++k) {
    const double x = -39 + (k * 37) % 79, y = -34 + (k * 53) % 69;
    points.emplace_back(x, y, 3.0 + 0.2 * x + 0.1 * y);
  }
  const TinMesh mesh = StartFromTiePoints(points, Region(), 5.0);
  double worst = 0;
  for (auto vh : mesh.vertices()) {
    const auto p = mesh.point(vh);
    worst = std::max(worst, std::abs(p[2] - (3.0 + 0.2 * p[0] + 0.1 * p[1])));
  }
  EXPECT_LT(worst, 1e-9);
}

// A tower 10 x 10 m and 25 m tall on flat ground: its roof's tie points lie above a
// region whose height range ends at 10 m (as one taken from the points' height
// percentiles does), and still lift the start's nodes over the tower to the roof.
TEST(StartTiePoints, TowerRoofAboveTheRegionsHeightRangeLiftsItsNodes) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> ux(-40, 40), uy(-35, 35), roof(-5, 5);
  std::normal_distribution<double> noise(0, 0.03);
  ImageBlock block;
  auto add = [&block](const Eigen::Vector3d& p) {
    TiePoint point;
    point.xyz = p;
    block.points.push_back(point);
  };
  while (block.points.size() < 400) {
    const double x = ux(rng), y = uy(rng);
    if (std::abs(x) < 5.5 && std::abs(y) < 5.5) continue;  // the tower's walls hide the ground
    add(Eigen::Vector3d(x, y, noise(rng)));
  }
  for (int i = 0; i < 40; ++i) add(Eigen::Vector3d(roof(rng), roof(rng), 25.0 + noise(rng)));
  add(Eigen::Vector3d(60.0, 0.0, 25.0));  // beyond the region's XY rectangle
  RegionOfInterest region = Region();
  region.min.z() = -1.0;
  region.max.z() = 10.0;

  const std::vector<Eigen::Vector3d> over = TiePointsOverFootprint(block, region);
  ASSERT_EQ(over.size(), 440u);
  EXPECT_EQ(TiePointsInRegion(block, region).size(), 400u);
  TiePointStartReport report;
  const TiePointHeightGrid grid = FitTiePointHeights(over, region, 4.0, {}, &report);
  std::cout << report.Brief() << "; node heights over the tower centre " << grid.At(0, 0) << ", its edges "
            << grid.At(-4, 0) << " " << grid.At(4, 0) << " m\n";
  EXPECT_EQ(report.points_in_region, 440);
  EXPECT_NEAR(grid.At(0, 0), 25.0, 0.1);
  EXPECT_GT(grid.At(4, 0), 20.0);  // 1 m inside the roof's edge
  EXPECT_GT(grid.At(-4, 0), 20.0);
  EXPECT_NEAR(grid.At(-20, 15), 0.0, 0.1);
  // The points inside the region's box alone leave the tower on the ground.
  const TiePointHeightGrid clipped = FitTiePointHeights(TiePointsInRegion(block, region), region, 4.0);
  EXPECT_NEAR(clipped.At(0, 0), 0.0, 0.5);
}

TEST(StartTiePoints, TooFewPointsAndAutoChoice) {
  const std::vector<Eigen::Vector3d> few = Points(10, 3);
  try {
    FitTiePointHeights(few, Region(), 4.0);
    FAIL() << "expected an error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("10 tie points over the region"), std::string::npos) << e.what();
  }
  const TiePointStartOptions options;
  EXPECT_TRUE(UseTiePointStart(StartSurfaceKind::kAuto, 20, false, options));
  EXPECT_FALSE(UseTiePointStart(StartSurfaceKind::kAuto, 19, false, options));
  EXPECT_FALSE(UseTiePointStart(StartSurfaceKind::kAuto, 400, true, options));
  EXPECT_FALSE(UseTiePointStart(StartSurfaceKind::kPlane, 400, false, options));
  EXPECT_TRUE(UseTiePointStart(StartSurfaceKind::kTiePoints, 0, true, options));
  EXPECT_THROW(StartSurfaceFromName("mesh"), std::invalid_argument);
}

}  // namespace
}  // namespace facets
