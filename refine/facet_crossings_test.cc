// FlattenCrossingFacets: two flat sheets a little apart whose TIN chords do not cross,
// the lower one with dome normals in its middle, so its G1 patches bulge up through the
// upper sheet. The repair must leave no crossing facets, move only the nodes of faces
// around the crossings, and by no more than the bulge.
#include "refine/facet_crossings.h"

#include <gtest/gtest.h>

#include <cmath>
#include <iostream>

#include "mesh/creases.h"
#include "mesh/surface_validity.h"

namespace facets {
namespace {

// Adds a flat square grid at height z (normals up) to `mesh`.
void AddSheet(TinMesh* mesh, double half, double spacing, double z) {
  StartGridOptions grid;
  grid.min = Eigen::Vector2d(-half, -half);
  grid.max = Eigen::Vector2d(half, half);
  grid.spacing = spacing;
  grid.plane_height = z;
  const TinMesh sheet = MakeStartGrid(grid);
  std::vector<TinMesh::VertexHandle> handles;
  for (auto v : sheet.vertices()) handles.push_back(mesh->add_vertex(sheet.point(v)));
  for (auto f : sheet.faces()) {
    std::vector<TinMesh::VertexHandle> corners;
    for (auto v : sheet.fv_range(f)) corners.push_back(handles[v.idx()]);
    mesh->add_face(corners);
  }
}

// Lower sheet (z = 0, 2 x 2 m, 0.25 m spacing) with dome normals within 0.6 m of the
// centre, upper sheet (1 x 1 m) flat at `gap`.
TinMesh TwoSheets(double gap) {
  TinMesh mesh;
  AddSheet(&mesh, 1.0, 0.25, 0.0);
  const int lower_vertices = static_cast<int>(mesh.n_vertices());
  AddSheet(&mesh, 0.5, 0.25, gap);
  for (auto v : mesh.vertices()) {
    const Eigen::Vector3d x = ToEigen(mesh.point(v));
    Eigen::Vector3d n(0, 0, 1);
    if (v.idx() < lower_vertices && x.head<2>().norm() < 0.6) n = Eigen::Vector3d(x.x(), x.y(), 0.5).normalized();
    mesh.set_normal(v, ToOpenMesh(n));
  }
  return mesh;
}

double HighestLowerNode(const Tessellation& tess, double below) {
  double top = -1e300;
  for (const auto& p : tess.points) {
    if (p.z() < below) top = std::max(top, p.z());
  }
  return top;
}

TEST(FacetCrossings, BulgingPatchesThroughAnotherSheetAreFlattenedUntilNoFacetsCross) {
  // The bulge of the dome patches over their chords (measured without the upper sheet).
  TinMesh lower;
  AddSheet(&lower, 1.0, 0.25, 0.0);
  for (auto v : lower.vertices()) {
    const Eigen::Vector3d x = ToEigen(lower.point(v));
    lower.set_normal(v, ToOpenMesh(x.head<2>().norm() < 0.6 ? Eigen::Vector3d(x.x(), x.y(), 0.5).normalized()
                                                            : Eigen::Vector3d(0, 0, 1)));
  }
  const double bulge = HighestLowerNode(Tessellate(lower), 1.0);
  ASSERT_GT(bulge, 0.005);
  const double gap = 0.5 * bulge;

  const TinMesh mesh = TwoSheets(gap);
  ASSERT_EQ(CountSelfIntersections(mesh), 0);  // the chords do not cross
  Tessellation tess = Tessellate(mesh);
  const Tessellation before = tess;
  const int crossing = CountCrossingFacets(tess);
  ASSERT_GT(crossing, 0);

  const FacetCrossingRepair repair = FlattenCrossingFacets(mesh, &tess);
  std::cout << "bulge " << bulge << " m, gap " << gap << " m: " << repair.Brief() << "\n";
  EXPECT_EQ(repair.pairs_found, crossing);
  EXPECT_EQ(repair.pairs_left, 0);
  EXPECT_EQ(CountCrossingFacets(tess), 0);
  EXPECT_EQ(repair.unchecked_facets, 0);
  EXPECT_GT(repair.max_move, 0.0);
  EXPECT_LE(repair.max_move, bulge + 1e-12);
  EXPECT_LE(repair.rounds, 3);
  // Nodes of faces outside 0.75 m of the centre (beyond the upper sheet and a ring) did
  // not move, bit for bit; every node of the lower sheet moved toward its chord (z = 0),
  // not past it; the upper sheet's flat patches did not move.
  const int lower_faces = 128;  // 8 x 8 cells of two triangles, added first
  int far = 0;
  for (size_t p = 0; p < tess.points.size(); ++p) {
    const Eigen::Vector3d& x = before.points[p];
    const Eigen::Vector3d& y = tess.points[p];
    if (tess.point_face[p] >= lower_faces) {
      EXPECT_EQ(y, x) << "upper node " << p;
      continue;
    }
    if (x.head<2>().lpNorm<Eigen::Infinity>() > 0.75) {
      ++far;
      EXPECT_EQ(y, x) << "node " << p;
    }
    EXPECT_LE(std::abs(y.z()), std::abs(x.z()) + 1e-15) << "node " << p;
    EXPECT_GE(y.z() * x.z(), 0.0) << "node " << p;
  }
  EXPECT_GT(far, 100);
  EXPECT_GT(repair.faces_changed, 0);
  EXPECT_LT(repair.faces_changed, lower_faces);
}

TEST(FacetCrossings, ChordsThatCrossAreReportedLeftAndTheRepairStops) {
  // The upper sheet lies in the lower one's plane: the TIN itself crosses there.
  TinMesh mesh;
  AddSheet(&mesh, 1.0, 0.25, 0.0);
  StartGridOptions grid;
  grid.min = Eigen::Vector2d(-0.4, -0.4);
  grid.max = Eigen::Vector2d(0.4, 0.4);
  grid.spacing = 0.2;
  grid.height = [](double x, double) { return x; };  // tilted through z = 0
  const TinMesh tilted = MakeStartGrid(grid);
  std::vector<TinMesh::VertexHandle> handles;
  for (auto v : tilted.vertices()) handles.push_back(mesh.add_vertex(tilted.point(v) + OpenMesh::Vec3d(0.03, 0.07, 0)));
  for (auto f : tilted.faces()) {
    std::vector<TinMesh::VertexHandle> corners;
    for (auto v : tilted.fv_range(f)) corners.push_back(handles[v.idx()]);
    mesh.add_face(corners);
  }
  UpdateVertexNormals(&mesh);
  ASSERT_GT(CountSelfIntersections(mesh), 0);
  Tessellation tess = Tessellate(mesh);
  const FacetCrossingRepair repair = FlattenCrossingFacets(mesh, &tess);
  std::cout << repair.Brief() << "\n";
  EXPECT_GT(repair.pairs_found, 0);
  EXPECT_GT(repair.pairs_left, 0);
  EXPECT_LE(repair.rounds, 3);  // weights 0.5, 0.25, 0, then nothing left to lower
}

// A steep gable (55 degrees) away from the origin, tessellated with its ridge and eaves
// as creases: the nodes duplicated along the creases agree to rounding only, and must
// not count as crossing facets; nothing moves.
TEST(FacetCrossings, CreaseDuplicatesAreNotCrossings) {
  StartGridOptions grid;
  grid.min = Eigen::Vector2d(312.3, -4471.1);
  grid.max = grid.min + Eigen::Vector2d(8, 8);
  grid.spacing = 0.5;
  const double ridge_y = grid.min.y() + 4.0;
  grid.height = [ridge_y](double, double y) {
    return 57.0 + std::max(0.0, 2.5 - std::abs(y - ridge_y)) * std::tan(55.0 * M_PI / 180.0);
  };
  TinMesh mesh = MakeStartGrid(grid);
  UpdateVertexNormals(&mesh);
  const CornerNormals creases = ComputeCornerNormals(mesh, 20.0);
  ASSERT_GT(creases.num_crease_edges, 40);
  Tessellation tess = Tessellate(mesh, BuildPatches(mesh, creases), creases);
  const Tessellation before = tess;
  EXPECT_EQ(CountCrossingFacets(tess), 0);
  const FacetCrossingRepair repair = FlattenCrossingFacets(mesh, &tess);
  EXPECT_EQ(repair.pairs_found, 0);
  EXPECT_EQ(repair.unchecked_facets, 0);
  EXPECT_EQ(repair.faces_changed, 0);
  EXPECT_EQ(tess.points, before.points);
}

}  // namespace
}  // namespace facets
