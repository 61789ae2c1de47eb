// Closed start surfaces for objects: an evenly triangulated ellipsoid, a TIN
// from a triangle list, and the check that a surface is closed and free of
// self-intersections (CGAL Polygon_mesh_processing).
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "mesh/tin.h"

namespace facets {

// x = centre + axes * diag(radii) * u for unit vectors u; axes orthonormal (columns).
struct Ellipsoid {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  Eigen::Matrix3d axes = Eigen::Matrix3d::Identity();
  Eigen::Vector3d radii = Eigen::Vector3d::Ones();
  double MeanRadius() const { return radii.mean(); }
};

// Class-I geodesic sphere: every icosahedron face cut into frequency^2 triangles and
// projected onto the ellipsoid, so any edge length is reachable (not only halvings).
// The frequency gives edges of about edge_length on a sphere of the mean radius;
// faces are counter-clockwise seen from outside (normals point out); vertex normals
// set. 20 frequency^2 faces, 10 frequency^2 + 2 vertices.
TinMesh MakeEllipsoidMesh(const Ellipsoid& ellipsoid, double edge_length);

// The convex hull of `points` (CGAL), grown by `inflate` (relative, about `centre`), as
// an evenly triangulated star-shaped mesh: the geodesic sphere's directions from
// `centre` (which must lie inside the hull) are cut with the hull. The sphere's
// frequency gives edges of about edge_length at the hull's mean distance from the
// centre; flat hull faces stretch some edges (the engine's quality pass splits them).
// Throws std::runtime_error when the points span no volume or the centre is outside.
TinMesh MakeHullMesh(const std::vector<Eigen::Vector3d>& points, const Eigen::Vector3d& centre,
                     double edge_length, double inflate);

// Mesh from points and triangles. Throws std::runtime_error naming `source_name` when a
// triangle refers to a missing vertex, is degenerate, or OpenMesh refuses it
// (non-manifold edge or vertex). Vertex normals set.
TinMesh TinFromTriangles(const std::vector<Eigen::Vector3d>& points,
                         const std::vector<Eigen::Vector3i>& triangles,
                         const std::string& source_name);

// The mesh's points and triangles (vertex and face order kept).
void TinPointsAndTriangles(const TinMesh& mesh, std::vector<Eigen::Vector3d>* points,
                           std::vector<Eigen::Vector3i>* triangles);

struct ClosedSurfaceCheck {
  int vertices = 0;             // after merging coincident points
  int triangles = 0;
  int border_edges = 0;         // 0 for a closed surface
  bool closed = false;          // no border edges, every edge between two triangles
  bool self_intersecting = true;
  double volume = 0.0;          // signed; > 0 when the normals point out
  std::string Brief() const;
};

// For each point, the index of the merged point it belongs to: points within `tolerance`
// of an earlier one take its index, merged indices count up from 0 in order of first
// appearance (tolerance <= 0: every point its own).
std::vector<int> MergeCoincidentPoints(const std::vector<Eigen::Vector3d>& points, double tolerance);

// Coincident points (within `merge_tolerance`) are merged first: a tessellation split
// along creases holds the same point twice, which is not a hole.
ClosedSurfaceCheck CheckClosedSurface(const std::vector<Eigen::Vector3d>& points,
                                      const std::vector<Eigen::Vector3i>& triangles,
                                      double merge_tolerance = 1e-9);
ClosedSurfaceCheck CheckClosedSurface(const TinMesh& mesh);

}  // namespace facets
