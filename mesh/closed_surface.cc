#include "mesh/closed_surface.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/measure.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/convex_hull_3.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <sstream>
#include <stdexcept>
#include <unordered_map>
#include <utility>

namespace facets {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using CgalMesh = CGAL::Surface_mesh<Kernel::Point_3>;
namespace PMP = CGAL::Polygon_mesh_processing;

// The 12 vertices and 20 faces of the icosahedron, faces oriented outward.
void Icosahedron(std::vector<Eigen::Vector3d>* vertices, std::vector<std::array<int, 3>>* faces) {
  const double phi = 0.5 * (1.0 + std::sqrt(5.0));
  *vertices = {{-1, phi, 0}, {1, phi, 0}, {-1, -phi, 0}, {1, -phi, 0},
               {0, -1, phi}, {0, 1, phi}, {0, -1, -phi}, {0, 1, -phi},
               {phi, 0, -1}, {phi, 0, 1}, {-phi, 0, -1}, {-phi, 0, 1}};
  for (auto& v : *vertices) v.normalize();
  *faces = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
            {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
            {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
            {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (auto& f : *faces) {
    const Eigen::Vector3d& a = (*vertices)[f[0]];
    const Eigen::Vector3d& b = (*vertices)[f[1]];
    const Eigen::Vector3d& c = (*vertices)[f[2]];
    if ((b - a).cross(c - a).dot(a + b + c) < 0.0) std::swap(f[1], f[2]);
  }
}

}  // namespace

TinMesh MakeHullMesh(const std::vector<Eigen::Vector3d>& points, const Eigen::Vector3d& centre,
                     double edge_length, double inflate) {
  if (points.size() < 4) throw std::runtime_error("convex hull: fewer than 4 points");
  std::vector<Kernel::Point_3> cgal_points;
  for (const auto& p : points) cgal_points.emplace_back(p.x(), p.y(), p.z());
  CgalMesh hull;
  CGAL::convex_hull_3(cgal_points.begin(), cgal_points.end(), hull);
  if (hull.number_of_faces() < 4) throw std::runtime_error("convex hull: the points span no volume");
  // Hull face planes n.x = d with outward unit n.
  std::vector<std::pair<Eigen::Vector3d, double>> planes;
  for (auto f : hull.faces()) {
    Eigen::Vector3d x[3];
    int k = 0;
    for (auto v : CGAL::vertices_around_face(hull.halfedge(f), hull)) {
      const auto& p = hull.point(v);
      x[k++] = Eigen::Vector3d(p.x(), p.y(), p.z());
    }
    Eigen::Vector3d n = (x[1] - x[0]).cross(x[2] - x[0]);
    if (n.norm() <= 0.0) continue;
    n.normalize();
    if (n.dot(x[0]) - n.dot(centre) <= 0.0) {
      throw std::runtime_error("convex hull: the centre lies outside the hull");
    }
    planes.emplace_back(n, n.dot(x[0]));
  }
  auto reach = [&](const Eigen::Vector3d& u) {  // distance from the centre to the hull along u
    double t = std::numeric_limits<double>::infinity();
    for (const auto& [n, d] : planes) {
      const double nu = n.dot(u);
      if (nu > 1e-12) t = std::min(t, (d - n.dot(centre)) / nu);
    }
    return t;
  };
  double mean = 0.0;
  for (const auto& p : points) mean += (p - centre).norm();
  mean /= static_cast<double>(points.size());
  // A unit sphere at the centre, each vertex moved out to the (inflated) hull.
  Ellipsoid unit;
  unit.centre = centre;
  unit.radii = Eigen::Vector3d::Constant(mean);
  TinMesh mesh = MakeEllipsoidMesh(unit, edge_length);
  for (auto vh : mesh.vertices()) {
    const Eigen::Vector3d u = (ToEigen(mesh.point(vh)) - centre).normalized();
    mesh.set_point(vh, ToOpenMesh(centre + (1.0 + inflate) * reach(u) * u));
  }
  UpdateVertexNormals(&mesh);
  return mesh;
}

TinMesh MakeEllipsoidMesh(const Ellipsoid& ellipsoid, double edge_length) {
  if (!(edge_length > 0.0)) throw std::invalid_argument("MakeEllipsoidMesh: edge_length must be > 0");
  if (!(ellipsoid.radii.array() > 0.0).all()) {
    throw std::invalid_argument("MakeEllipsoidMesh: radii must be > 0");
  }
  std::vector<Eigen::Vector3d> corners;
  std::vector<std::array<int, 3>> ico;
  Icosahedron(&corners, &ico);
  // The icosahedron's edge on the unit sphere is 1.0515; the geodesic edges of
  // frequency n are about that / n.
  const int n = std::max(1, static_cast<int>(std::lround(1.0515 * ellipsoid.MeanRadius() / edge_length)));

  // A lattice point is the weighted corner sum; keyed by its sorted (corner, weight)
  // pairs it is the same point for every face that shares it, computed identically.
  std::map<std::vector<std::pair<int, int>>, int> index;
  std::vector<Eigen::Vector3d> points;
  std::vector<Eigen::Vector3i> triangles;
  auto lattice = [&](const std::array<int, 3>& f, int i, int j) {
    std::vector<std::pair<int, int>> key;
    const int w[3] = {n - i - j, i, j};
    for (int k = 0; k < 3; ++k) {
      if (w[k] > 0) key.emplace_back(f[k], w[k]);
    }
    std::sort(key.begin(), key.end());
    auto [it, added] = index.emplace(key, static_cast<int>(points.size()));
    if (added) {
      Eigen::Vector3d u = Eigen::Vector3d::Zero();
      for (const auto& [corner, weight] : key) u += weight * corners[corner];
      u.normalize();
      points.push_back(ellipsoid.centre + ellipsoid.axes * ellipsoid.radii.cwiseProduct(u));
    }
    return it->second;
  };
  const bool mirrored = ellipsoid.axes.determinant() < 0.0;
  auto add = [&](int a, int b, int c) {
    triangles.emplace_back(a, mirrored ? c : b, mirrored ? b : c);
  };
  for (const auto& f : ico) {
    for (int j = 0; j < n; ++j) {
      for (int i = 0; i + j < n; ++i) {
        add(lattice(f, i, j), lattice(f, i + 1, j), lattice(f, i, j + 1));
        if (i + j < n - 1) add(lattice(f, i + 1, j), lattice(f, i + 1, j + 1), lattice(f, i, j + 1));
      }
    }
  }
  return TinFromTriangles(points, triangles, "ellipsoid");
}

TinMesh TinFromTriangles(const std::vector<Eigen::Vector3d>& points,
                         const std::vector<Eigen::Vector3i>& triangles,
                         const std::string& source_name) {
  TinMesh mesh;
  std::vector<TinMesh::VertexHandle> handles;
  handles.reserve(points.size());
  for (size_t i = 0; i < points.size(); ++i) {
    if (!points[i].allFinite()) {
      throw std::runtime_error(source_name + ": vertex " + std::to_string(i) + " is not finite");
    }
    handles.push_back(mesh.add_vertex(ToOpenMesh(points[i])));
  }
  for (size_t t = 0; t < triangles.size(); ++t) {
    const Eigen::Vector3i& tri = triangles[t];
    for (int c = 0; c < 3; ++c) {
      if (tri[c] < 0 || tri[c] >= static_cast<int>(points.size())) {
        throw std::runtime_error(source_name + ": triangle " + std::to_string(t) +
                                 " refers to vertex " + std::to_string(tri[c]) + " of " +
                                 std::to_string(points.size()));
      }
    }
    if (tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2]) {
      throw std::runtime_error(source_name + ": triangle " + std::to_string(t) + " is degenerate");
    }
    if (!mesh.add_face(handles[tri[0]], handles[tri[1]], handles[tri[2]]).is_valid()) {
      throw std::runtime_error(source_name + ": triangle " + std::to_string(t) +
                               " makes a non-manifold edge or vertex (or is flipped against "
                               "its neighbours)");
    }
  }
  if (mesh.n_faces() == 0) throw std::runtime_error(source_name + ": contains no triangles");
  UpdateVertexNormals(&mesh);
  return mesh;
}

std::string ClosedSurfaceCheck::Brief() const {
  std::ostringstream out;
  out << vertices << " vertices, " << triangles << " triangles, "
      << (closed ? "closed" : "NOT closed (" + std::to_string(border_edges) + " border edges)")
      << ", " << (self_intersecting ? "SELF-INTERSECTING" : "no self-intersections")
      << ", volume " << volume;
  return out.str();
}

std::vector<int> MergeCoincidentPoints(const std::vector<Eigen::Vector3d>& points, double tolerance) {
  // Hash cells of the tolerance, search the 27 around a point.
  const double cell = std::max(tolerance, 1e-15);
  auto key = [&](const Eigen::Vector3d& p, int dx, int dy, int dz) {
    const long long x = static_cast<long long>(std::floor(p.x() / cell)) + dx;
    const long long y = static_cast<long long>(std::floor(p.y() / cell)) + dy;
    const long long z = static_cast<long long>(std::floor(p.z() / cell)) + dz;
    return (x * 73856093LL) ^ (y * 19349663LL) ^ (z * 83492791LL);
  };
  std::unordered_multimap<long long, int> cells;
  std::vector<int> merged(points.size());
  int count = 0;
  for (size_t i = 0; i < points.size(); ++i) {
    int found = -1;
    if (tolerance > 0.0) {
      for (int dx = -1; dx <= 1 && found < 0; ++dx) {
        for (int dy = -1; dy <= 1 && found < 0; ++dy) {
          for (int dz = -1; dz <= 1 && found < 0; ++dz) {
            auto range = cells.equal_range(key(points[i], dx, dy, dz));
            for (auto it = range.first; it != range.second; ++it) {
              if ((points[it->second] - points[i]).norm() <= tolerance) {
                found = merged[it->second];
                break;
              }
            }
          }
        }
      }
    }
    merged[i] = found >= 0 ? found : count++;
    if (tolerance > 0.0) cells.emplace(key(points[i], 0, 0, 0), static_cast<int>(i));
  }
  return merged;
}

ClosedSurfaceCheck CheckClosedSurface(const std::vector<Eigen::Vector3d>& points,
                                      const std::vector<Eigen::Vector3i>& triangles,
                                      double merge_tolerance) {
  const std::vector<int> merged = MergeCoincidentPoints(points, merge_tolerance);
  std::vector<Kernel::Point_3> unique;
  for (size_t i = 0; i < points.size(); ++i) {
    if (merged[i] == static_cast<int>(unique.size())) unique.emplace_back(points[i].x(), points[i].y(), points[i].z());
  }
  std::vector<std::vector<std::size_t>> polygons;
  polygons.reserve(triangles.size());
  for (const auto& t : triangles) {
    polygons.push_back({static_cast<std::size_t>(merged[t[0]]), static_cast<std::size_t>(merged[t[1]]),
                        static_cast<std::size_t>(merged[t[2]])});
  }
  ClosedSurfaceCheck check;
  check.vertices = static_cast<int>(unique.size());
  check.triangles = static_cast<int>(triangles.size());
  if (!PMP::is_polygon_soup_a_polygon_mesh(polygons)) {
    // Non-manifold or inconsistently oriented: neither closed nor a valid surface.
    check.border_edges = -1;
    return check;
  }
  CgalMesh mesh;
  PMP::polygon_soup_to_polygon_mesh(unique, polygons, mesh);
  for (auto h : mesh.halfedges()) {
    if (mesh.is_border(h)) ++check.border_edges;
  }
  check.closed = check.border_edges == 0;
  check.self_intersecting = PMP::does_self_intersect<CGAL::Parallel_if_available_tag>(mesh);
  if (check.closed) check.volume = PMP::volume(mesh);
  return check;
}

void TinPointsAndTriangles(const TinMesh& mesh, std::vector<Eigen::Vector3d>* points,
                           std::vector<Eigen::Vector3i>* triangles) {
  points->clear();
  triangles->clear();
  for (auto vh : mesh.vertices()) points->push_back(ToEigen(mesh.point(vh)));
  for (auto fh : mesh.faces()) {
    Eigen::Vector3i t;
    int k = 0;
    for (auto vh : mesh.fv_range(fh)) t[k++] = vh.idx();
    triangles->push_back(t);
  }
}

ClosedSurfaceCheck CheckClosedSurface(const TinMesh& mesh) {
  std::vector<Eigen::Vector3d> points;
  std::vector<Eigen::Vector3i> triangles;
  TinPointsAndTriangles(mesh, &points, &triangles);
  return CheckClosedSurface(points, triangles, 0.0);
}

}  // namespace facets
