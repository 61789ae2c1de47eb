#include "refine/wall_corners.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "mesh/local_ops.h"
#include "mesh/surface_validity.h"

namespace facets {
namespace {

constexpr double kH = 0.5;  // edge length of the test walls

// Two walls 4 m high meeting at a vertical corner on the Z axis: the first along -X on
// y = 0 (outward +Y), the second turned by `turn_deg` about Z away from it (90: along -Y
// on x = 0, outward +X), 3 m each; columns every kH along the footprint, none on the
// corner (the grid starts half a column off it), so the edges across the corner cut it
// off, as on an adjusted TIN. The two columns beside the corner are pulled `crumple` m
// into the building, each along its own wall's normal. Below z = 1.5 the first wall
// leans `foot_lean_deg` inward (a lower band a few degrees off, as adjusted walls come
// out near a corner).
TinMesh CornerWalls(double turn_deg, double crumple, double foot_lean_deg = 0.0) {
  const double turn = turn_deg * M_PI / 180.0;
  const Eigen::Vector2d along_b(std::cos(-turn), std::sin(-turn));
  auto footprint = [&](double s) -> Eigen::Vector2d {
    return s <= 0.0 ? Eigen::Vector2d(s, 0.0) : Eigen::Vector2d(s * along_b);
  };
  const int columns = 12, rows = 9;  // s = -2.75 .. 2.75, z = 0 .. 4
  TinMesh mesh;
  std::vector<TinMesh::VertexHandle> v(columns * rows);
  for (int i = 0; i < columns; ++i) {
    const double s = -3.0 + (i + 0.5) * kH;
    Eigen::Vector2d p = footprint(s);
    if (std::abs(s) < kH) {
      // Inward: -Y for the first wall, minus the second wall's outward normal for the other.
      const Eigen::Vector2d inward = s < 0.0 ? Eigen::Vector2d(0.0, -1.0) : Eigen::Vector2d(along_b.y(), -along_b.x());
      p += crumple * inward;
    }
    for (int j = 0; j < rows; ++j) {
      const double z = j * kH;
      const double lean = s < 0.0 && z < 1.5 ? (1.5 - z) * std::tan(foot_lean_deg * M_PI / 180.0) : 0.0;
      v[i * rows + j] = mesh.add_vertex({p.x(), p.y() - lean, z});
    }
  }
  for (int i = 0; i + 1 < columns; ++i) {
    for (int j = 0; j + 1 < rows; ++j) {
      const auto a = v[i * rows + j], b = v[(i + 1) * rows + j], c = v[(i + 1) * rows + j + 1], d = v[i * rows + j + 1];
      mesh.add_face(a, c, b);  // outward: Z x the footprint's direction
      mesh.add_face(a, d, c);
    }
  }
  UpdateVertexNormals(&mesh);
  return mesh;
}

WallCornerOptions Options() {
  WallCornerOptions options;
  options.edge_length = kH;
  return options;
}

TEST(WallCorners, CrumpledCornerGetsAChainOnItsLineAndStaysUnfolded) {
  TinMesh mesh = CornerWalls(90.0, 0.15);
  const WallCornerSearch search = FindWallCorners(mesh, Options());
  ASSERT_EQ(search.corners.size(), 1u);
  const WallCorner& corner = search.corners[0];
  EXPECT_EQ(search.wall_regions, 2);
  EXPECT_NEAR(corner.point.x(), 0.0, 1e-9);
  EXPECT_NEAR(corner.point.y(), 0.0, 1e-9);
  EXPECT_NEAR(std::abs(corner.direction.z()), 1.0, 1e-12);
  EXPECT_TRUE(corner.convex);
  // Half an edge short of the foot and the top (z 0.25 .. 3.75): rows 1..7 of the two
  // crumpled columns, and of the next ones, 0.75 m from the corner, as rounding puts them
  // within 1.5 edges or not.
  EXPECT_NEAR(corner.half_length, 1.75, 1e-9);
  EXPECT_GE(corner.band.size(), 14u);
  EXPECT_LE(corner.band.size(), 28u);

  const TinMesh before = mesh;
  const CornerLaying laid = LayCornerOntoWalls(&mesh, corner, Options());
  // The crumpled columns go onto their walls, 0.25 m from the corner, within the snap
  // distance (0.3 m) of the line: onto it. Both on the line would leave the faces between
  // them without area, so one column goes back; the outer columns stand on their walls.
  EXPECT_EQ(laid.moved, 7);
  EXPECT_EQ(laid.on_line, 7);
  EXPECT_EQ(laid.left_off, 7);
  EXPECT_NEAR(laid.max_move, std::hypot(0.25, 0.15), 1e-9);
  int on_line = 0, changed = 0;
  for (auto vh : mesh.vertices()) {
    const Eigen::Vector3d p = ToEigen(mesh.point(vh));
    if (std::hypot(p.x(), p.y()) < 1e-9) ++on_line;
    if (mesh.point(vh) != before.point(vh)) ++changed;
  }
  EXPECT_EQ(on_line, 7);
  EXPECT_EQ(changed, 7);
  EXPECT_EQ(CountFoldedFaces(mesh), 0);
  EXPECT_EQ(CountSelfIntersections(mesh), 0);
}

// Distance from p to triangle (a, b, c) (closest point by regions, Ericson 2005, 5.1.5).
double PointTriangleDistance(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                             const Eigen::Vector3d& c) {
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return (p - a).norm();
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return (p - b).norm();
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return (p - (a + d1 / (d1 - d3) * ab)).norm();
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return (p - c).norm();
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return (p - (a + d2 / (d2 - d6) * ac)).norm();
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0) {
    return (p - (b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b))).norm();
  }
  const double den = 1.0 / (va + vb + vc);
  return (p - (a + ab * (vb * den) + ac * (vc * den))).norm();
}

// Mean distance of the true corner line (the Z axis, z 1 .. 10 m every 0.25 m) to the
// TIN's chord triangles.
double MeanCornerDistance(const TinMesh& mesh) {
  double sum = 0.0;
  int n = 0;
  for (double z = 1.0; z <= 10.0; z += 0.25, ++n) {
    const Eigen::Vector3d p(0.0, 0.0, z);
    double best = 1e30;
    for (auto f : mesh.faces()) {
      auto it = mesh.cfv_iter(f);
      const Eigen::Vector3d a = ToEigen(mesh.point(*it)), b = ToEigen(mesh.point(*++it)), c = ToEigen(mesh.point(*++it));
      best = std::min(best, PointTriangleDistance(p, a, b, c));
    }
    sum += best;
  }
  return sum / n;
}

double MeanLineDistance(const TinMesh& mesh, double y, double z) {
  double sum = 0.0;
  int n = 0;
  for (double x = -2.0; x <= 2.0; x += 0.25, ++n) {
    double best = 1e30;
    for (auto f : mesh.faces()) {
      auto it = mesh.cfv_iter(f);
      const Eigen::Vector3d a = ToEigen(mesh.point(*it)), b = ToEigen(mesh.point(*++it)), c = ToEigen(mesh.point(*++it));
      best = std::min(best, PointTriangleDistance(Eigen::Vector3d(x, y, z), a, b, c));
    }
    sum += best;
  }
  return sum / n;
}

// A real corner: tests/data/corner_patch.ply is the finest TIN of block_oblique
// (--thorough-walls, Embree AVX2, session 31) around the 12 m building's north-east
// corner, moved so that the corner is the Z axis (walls x = 0 and y = 0, 0.72 m edges).
// As adjusted, the corner line lies 0.33 m from the surface on average (up to 0.77 m:
// the faces cut it off); after the engine's steps (long edges split, the corner laid),
// measured 0.18 m on average.
TEST(WallCorners, RealCornerOfTheObliqueBlockComesCloserToItsLine) {
  TinMesh mesh = LoadStartMesh(std::string(FACETS_SOURCE_DIR) + "/tests/data/corner_patch.ply");
  const double as_adjusted = MeanCornerDistance(mesh);
  EXPECT_GT(as_adjusted, 0.3);
  QualityOptions quality;
  quality.target_edge_length = 0.72;
  quality.max_rounds = 2;
  QualityPass(&mesh, quality);
  UpdateVertexNormals(&mesh);
  const int crossing = CountSelfIntersections(mesh), folded = CountFoldedFaces(mesh);
  WallCornerOptions options;
  options.edge_length = 0.72;
  const WallCornerSearch search = FindWallCorners(mesh, options);
  ASSERT_EQ(search.corners.size(), 1u);
  const WallCorner& corner = search.corners[0];
  EXPECT_LT(std::hypot(corner.point.x(), corner.point.y()), 0.05);
  EXPECT_GT(std::abs(corner.direction.z()), 0.999);
  EXPECT_TRUE(corner.convex);
  const CornerLaying laid = LayCornerOntoWalls(&mesh, corner, options);
  UpdateVertexNormals(&mesh);
  EXPECT_GE(laid.on_line, 4);
  EXPECT_LE(laid.max_move, 1.5 * 0.72);
  EXPECT_LT(MeanCornerDistance(mesh), 0.65 * as_adjusted);
  EXPECT_LE(CountSelfIntersections(mesh), crossing);
  EXPECT_LE(CountFoldedFaces(mesh), folded);
}

// A wall's profile extruded along X (x -3 .. 3, columns every kH): the ground z = 0 for
// y -3 .. 0, the wall y = 0 (outward -Y) up to z = 4, a flat roof z = 4 for y 0 .. 3.
// Nodes every kH along the profile, none on its two creases (the grid starts half a step
// off), so the faces cut the foot and the eave off, as on an adjusted TIN; the foot's two
// nearest nodes are pulled `crumple` m out into the air (a fillet, as the regularisation
// rounds a foot), the eave's two pushed into the building.
TinMesh FootAndEave(double crumple) {
  const int columns = 13, nodes = 20;  // profile length 10 m
  auto profile = [&](double s) -> Eigen::Vector2d {  // (y, z)
    if (s <= 3.0) return {s - 3.0, 0.0};
    if (s <= 7.0) return {0.0, s - 3.0};
    return {s - 7.0, 4.0};
  };
  TinMesh mesh;
  std::vector<TinMesh::VertexHandle> v(columns * nodes);
  for (int j = 0; j < nodes; ++j) {
    const double s = (j + 0.5) * kH;
    Eigen::Vector2d p = profile(s);
    if (std::abs(s - 3.0) < kH) p += crumple * (s < 3.0 ? Eigen::Vector2d(0.0, 1.0) : Eigen::Vector2d(-1.0, 0.0));
    if (std::abs(s - 7.0) < kH) p += crumple * (s < 7.0 ? Eigen::Vector2d(1.0, 0.0) : Eigen::Vector2d(0.0, -1.0));
    for (int i = 0; i < columns; ++i) v[i * nodes + j] = mesh.add_vertex({-3.0 + i * kH, p.x(), p.y()});
  }
  for (int i = 0; i + 1 < columns; ++i) {
    for (int j = 0; j + 1 < nodes; ++j) {
      const auto a = v[i * nodes + j], b = v[(i + 1) * nodes + j], c = v[(i + 1) * nodes + j + 1], d = v[i * nodes + j + 1];
      mesh.add_face(a, b, c);  // outward: +Z on the ground, -Y on the wall
      mesh.add_face(a, c, d);
    }
  }
  UpdateVertexNormals(&mesh);
  return mesh;
}

// Mean distance of a line along X (at y, z; x -2 .. 2 every 0.25 m) to the TIN's chords.
double MeanLineDistance(const TinMesh& mesh, double y, double z);

TEST(WallCorners, FootAndEaveAreFoundOnlyWhenAskedAndLaidOntoTheirPlanes) {
  TinMesh mesh = FootAndEave(0.15);
  const WallCornerSearch vertical_only = FindWallCorners(mesh, Options());
  EXPECT_EQ(vertical_only.wall_regions, 1);
  EXPECT_TRUE(vertical_only.corners.empty());
  WallCornerOptions options = Options();
  options.feet = options.eaves = true;
  const WallCornerSearch search = FindWallCorners(mesh, options);
  ASSERT_EQ(search.corners.size(), 2u);
  ASSERT_EQ(search.count(CreaseKind::kFoot), 1);
  ASSERT_EQ(search.count(CreaseKind::kEave), 1);
  const double foot_before = MeanLineDistance(mesh, 0.0, 0.0), eave_before = MeanLineDistance(mesh, 0.0, 4.0);
  EXPECT_GT(foot_before, 0.15);
  EXPECT_GT(eave_before, 0.15);
  for (const WallCorner& crease : search.corners) {
    const double height = crease.kind == CreaseKind::kFoot ? 0.0 : 4.0;
    EXPECT_EQ(crease.convex, crease.kind == CreaseKind::kEave);
    EXPECT_NEAR(std::abs(crease.direction.x()), 1.0, 1e-9);
    EXPECT_NEAR(crease.point.y(), 0.0, 1e-9);
    EXPECT_NEAR(crease.point.z(), height, 1e-9);
    // Half an edge short of the ends (x -3 and 3); the band leaves the border columns out.
    EXPECT_NEAR(crease.half_length, 2.75, 1e-9);
    const CornerLaying laid = LayCornerOntoWalls(&mesh, crease, options);
    UpdateVertexNormals(&mesh);
    // Both crumpled rows of the 11 inner columns reach the line's snap distance; one row
    // on the line, the other back where it was (both there would leave faces without area).
    EXPECT_EQ(laid.on_line, 11);
    EXPECT_EQ(laid.left_off, 11);
  }
  EXPECT_LT(MeanLineDistance(mesh, 0.0, 0.0), 0.1 * foot_before);
  EXPECT_LT(MeanLineDistance(mesh, 0.0, 4.0), 0.1 * eave_before);
  EXPECT_EQ(CountFoldedFaces(mesh), 0);
  EXPECT_EQ(CountSelfIntersections(mesh), 0);
}

TEST(WallCorners, GentleBendIsNoCorner) {
  // Normals 30 degrees apart: a bend of one wall, not a corner between two.
  TinMesh mesh = CornerWalls(30.0, 0.0);
  const WallCornerSearch search = FindWallCorners(mesh, Options());
  EXPECT_EQ(search.wall_regions, 2);
  EXPECT_TRUE(search.corners.empty());
}

TEST(WallCorners, ShallowCornerIsLeftAboveTheLeastAngle) {
  // Normals 50 degrees apart (a chamfer's against its wall encloses about 45): no corner
  // with the default least angle of 60 degrees, one with 45; walls 61 degrees apart make
  // one with the default.
  TinMesh mesh = CornerWalls(50.0, 0.0);
  EXPECT_TRUE(FindWallCorners(mesh, Options()).corners.empty());
  WallCornerOptions options = Options();
  options.min_corner_angle_deg = 45.0;
  const WallCornerSearch shallow = FindWallCorners(mesh, options);
  ASSERT_EQ(shallow.corners.size(), 1u);
  EXPECT_NEAR(shallow.corners[0].angle_deg(), 50.0, 1.0);
  EXPECT_EQ(FindWallCorners(CornerWalls(61.0, 0.0), Options()).corners.size(), 1u);
}

TEST(WallCorners, WallGrownInPiecesIsMergedAndItsCornerSpansTheHeight) {
  // The first wall's lower band leans 6 degrees: its faces stop the growth of the wall's
  // region a little below the kink and make a region of their own, which alone runs
  // beside the corner over less than two edges.
  TinMesh mesh = CornerWalls(90.0, 0.0, 6.0);
  WallCornerOptions apart = Options();
  apart.merge_wall_pieces = false;
  const WallCornerSearch pieces = FindWallCorners(mesh, apart);
  EXPECT_EQ(pieces.wall_regions, 3);
  EXPECT_EQ(pieces.merged_walls, 0);
  for (const WallCorner& corner : pieces.corners) EXPECT_LT(corner.half_length, 1.5);

  const WallCornerSearch merged = FindWallCorners(mesh, Options());
  EXPECT_EQ(merged.merged_walls, 1);
  EXPECT_EQ(merged.wall_regions, 2);
  ASSERT_EQ(merged.corners.size(), 1u);
  // Foot to top, half an edge short of each (the merged plane leans a little: 1.747).
  EXPECT_NEAR(merged.corners[0].half_length, 1.75, 0.01);
  EXPECT_NEAR(merged.corners[0].angle_deg(), 90.0, 3.0);
  // A wall 30 degrees off its neighbour is not merged into it.
  EXPECT_EQ(FindWallCorners(CornerWalls(30.0, 0.0), Options()).merged_walls, 0);
}

TEST(WallCorners, OptionsAreChecked) {
  WallCornerOptions options = Options();
  options.snap = 2.0;  // beyond the band
  EXPECT_THROW(options.Check(), std::invalid_argument);
  options = Options();
  options.edge_length = 0.0;
  EXPECT_THROW(options.Check(), std::invalid_argument);
  options = Options();
  options.min_corner_angle_deg = 30.0;
  EXPECT_THROW(options.Check(), std::invalid_argument);
  options = Options();
  options.local_fit = 0.0;
  EXPECT_THROW(options.Check(), std::invalid_argument);
}

}  // namespace
}  // namespace facets
