// The spatial TIN: a half-edge triangle mesh (OpenMesh) with double-precision points
// and vertex normals, vertices anywhere in R^3 (DESIGN.md section 3).
//
// Vertex normals are part of the surface model: together with the points they define
// the G1 surface (mesh/g1_patch.h). UpdateVertexNormals sets them to the normalised mean
// of the adjacent unit face normals; operations that must keep the surface's shape
// (subdivision, splits, smoothing) set them from the G1 surface instead.
#pragma once

#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>

#include <Eigen/Core>
#include <array>
#include <functional>
#include <string>
#include <vector>

#include "mesh/g1_patch.h"

namespace facets {

struct TinTraits : public OpenMesh::DefaultTraits {
  using Point = OpenMesh::Vec3d;
  using Normal = OpenMesh::Vec3d;
  VertexAttributes(OpenMesh::Attributes::Normal | OpenMesh::Attributes::Status);
  FaceAttributes(OpenMesh::Attributes::Normal | OpenMesh::Attributes::Status);
  EdgeAttributes(OpenMesh::Attributes::Status);
  HalfedgeAttributes(OpenMesh::Attributes::PrevHalfedge | OpenMesh::Attributes::Status);
};
using TinMesh = OpenMesh::TriMesh_ArrayKernelT<TinTraits>;

inline Eigen::Vector3d ToEigen(const OpenMesh::Vec3d& v) { return {v[0], v[1], v[2]}; }
inline OpenMesh::Vec3d ToOpenMesh(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }

// Regular start grid over a rectangle in the XY plane of local object coordinates.
struct StartGridOptions {
  // Rectangle covered by the grid; the last row/column lands exactly on max.
  Eigen::Vector2d min = Eigen::Vector2d(0.0, 0.0);
  Eigen::Vector2d max = Eigen::Vector2d(1.0, 1.0);
  // Target grid spacing; the actual spacing is range / ceil(range / spacing) so the
  // rectangle is covered exactly.
  double spacing = 0.1;
  // Height of the start surface Z(x, y). Empty: the plane Z = plane_height.
  std::function<double(double, double)> height;
  double plane_height = 0.0;

  // Throws std::invalid_argument naming the bad field.
  void Check() const;
};

// Points on the start surface over a regular grid, triangulated once by CGAL's 2D
// Delaunay triangulation of their XY positions; faces are counter-clockwise seen from
// +Z, so the normals point up. Vertex normals are set (UpdateVertexNormals).
TinMesh MakeStartGrid(const StartGridOptions& options);

// Start mesh from a PLY/OBJ/OFF/STL file (OpenMesh reader). Polygons are triangulated.
// Throws std::runtime_error naming the file when it is missing, unreadable or holds no
// triangles. Vertex normals are recomputed (UpdateVertexNormals).
TinMesh LoadStartMesh(const std::string& path);

// Face normals (unit) and vertex normals = normalised mean of the adjacent unit face
// normals, weighted by the corner angle at the vertex. Isolated vertices keep their normal.
void UpdateVertexNormals(TinMesh* mesh);

// The three vertex indices of every face, in face order (fv_range order).
std::vector<std::array<int, 3>> FaceVertices(const TinMesh& mesh);

// G1 patch of face fh from its three vertices and vertex normals, in face order.
G1Patch FacePatch(const TinMesh& mesh, TinMesh::FaceHandle fh);
// One patch per face, indexed by face index (TBB-parallel).
std::vector<G1Patch> BuildPatches(const TinMesh& mesh);
// Boundary curve of the edge, running from the edge's halfedge 0 from- to to-vertex.
EdgeCurve MakeEdgeCurve(const TinMesh& mesh, TinMesh::EdgeHandle eh);

}  // namespace facets
