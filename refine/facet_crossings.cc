#include "refine/facet_crossings.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <iterator>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "mesh/closed_surface.h"

namespace facets {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using CgalMesh = CGAL::Surface_mesh<Kernel::Point_3>;

// Crossing facet pairs (indices into tess.triangles), and the facets that could not be
// checked (non-manifold once coinciding nodes are merged).
struct CrossingPairs {
  std::vector<std::pair<int, int>> pairs;
  int unchecked = 0;
};

CrossingPairs FindCrossingTriangles(const std::vector<Eigen::Vector3d>& points,
                                    const std::vector<Eigen::Vector3i>& triangles) {
  // Crease duplicates are evaluated once per side: they agree to rounding, not bit for
  // bit, and unmerged they would count as crossing (facets meeting along an edge).
  Eigen::AlignedBox3d box;
  for (const auto& p : points) box.extend(p);
  const double tolerance = 1e-9 * (1.0 + (points.empty() ? 0.0 : box.diagonal().norm()));
  const std::vector<int> merged = MergeCoincidentPoints(points, tolerance);
  CgalMesh cgal;
  std::vector<CgalMesh::Vertex_index> vertex_of(points.size());
  std::vector<CgalMesh::Vertex_index> merged_vertex;
  for (size_t p = 0; p < points.size(); ++p) {
    if (merged[p] == static_cast<int>(merged_vertex.size())) {
      const Eigen::Vector3d& x = points[p];
      merged_vertex.push_back(cgal.add_vertex(Kernel::Point_3(x.x(), x.y(), x.z())));
    }
    vertex_of[p] = merged_vertex[merged[p]];
  }
  CrossingPairs result;
  std::vector<int> facet_of_face;  // CGAL face index -> facet
  facet_of_face.reserve(triangles.size());
  for (size_t s = 0; s < triangles.size(); ++s) {
    const Eigen::Vector3i& t = triangles[s];
    for (int c = 0; c < 3; ++c) {
      if (t[c] < 0 || t[c] >= static_cast<int>(points.size())) {
        throw std::invalid_argument("triangle " + std::to_string(s) + " refers to point " +
                                    std::to_string(t[c]) + " of " + std::to_string(points.size()));
      }
    }
    const CgalMesh::Vertex_index a = vertex_of[t[0]], b = vertex_of[t[1]], c = vertex_of[t[2]];
    if (a == b || b == c || a == c) {  // a facet collapsed to a point or segment
      ++result.unchecked;
      continue;
    }
    const CgalMesh::Face_index f = cgal.add_face(a, b, c);
    if (f == CgalMesh::null_face()) {
      ++result.unchecked;
      continue;
    }
    facet_of_face.push_back(static_cast<int>(s));
  }
  std::vector<std::pair<CgalMesh::Face_index, CgalMesh::Face_index>> pairs;
  CGAL::Polygon_mesh_processing::self_intersections(cgal, std::back_inserter(pairs));
  result.pairs.reserve(pairs.size());
  for (const auto& [f, g] : pairs) {
    result.pairs.emplace_back(facet_of_face[static_cast<int>(f)], facet_of_face[static_cast<int>(g)]);
  }
  return result;
}

}  // namespace

std::string FacetCrossingRepair::Brief() const {
  std::ostringstream out;
  out << pairs_found << " crossing facet pairs";
  if (pairs_found > 0) {
    out << ", " << faces_changed << " TIN faces pulled toward their chords in " << rounds
        << " rounds (largest node move " << max_move << " m), " << pairs_left << " pairs left";
  }
  if (unchecked_facets > 0) out << ", " << unchecked_facets << " facets not checked";
  return out.str();
}

int CountCrossingFacets(const Tessellation& tess) {
  return static_cast<int>(FindCrossingTriangles(tess.points, tess.triangles).pairs.size());
}

TriangleCrossings CountCrossingTriangles(const std::vector<Eigen::Vector3d>& points,
                                         const std::vector<Eigen::Vector3i>& triangles) {
  const CrossingPairs found = FindCrossingTriangles(points, triangles);
  return {static_cast<int>(found.pairs.size()), found.unchecked};
}

FacetCrossingRepair FlattenCrossingFacets(const TinMesh& mesh, Tessellation* tess, int max_rounds) {
  if (tess->NumFaces() != static_cast<int>(mesh.n_faces())) {
    throw std::invalid_argument("FlattenCrossingFacets: the tessellation has " +
                                std::to_string(tess->NumFaces()) + " faces, the TIN " +
                                std::to_string(mesh.n_faces()));
  }
  const std::vector<std::array<int, 3>> face_vertices = FaceVertices(mesh);
  // Each node as chord point + offset of the patch from it.
  const size_t n = tess->points.size();
  std::vector<Eigen::Vector3d> chord(n), offset(n);
  for (size_t p = 0; p < n; ++p) {
    const auto& fv = face_vertices[tess->point_face[p]];
    const Eigen::Vector3d& b = tess->point_barycentric[p];
    chord[p] = Eigen::Vector3d::Zero();
    for (int i = 0; i < 3; ++i) chord[p] += b[i] * ToEigen(mesh.point(TinMesh::VertexHandle(fv[i])));
    offset[p] = tess->points[p] - chord[p];
  }
  std::vector<double> weight(mesh.n_vertices(), 1.0);
  FacetCrossingRepair repair;
  for (int round = 0;; ++round) {
    const CrossingPairs crossing = FindCrossingTriangles(tess->points, tess->triangles);
    if (round == 0) {
      repair.pairs_found = static_cast<int>(crossing.pairs.size());
      repair.unchecked_facets = crossing.unchecked;
    }
    repair.pairs_left = static_cast<int>(crossing.pairs.size());
    if (crossing.pairs.empty() || round == max_rounds) break;
    // Lower the weights of the crossing faces' vertices one step: 1, 0.5, 0.25, 0.
    std::vector<bool> lowered(mesh.n_vertices(), false);
    bool changed = false;
    for (const auto& [s, t] : crossing.pairs) {
      for (const int facet : {s, t}) {
        for (const int v : face_vertices[facet / kSubTrianglesPerFace]) {
          if (lowered[v] || weight[v] == 0.0) continue;
          lowered[v] = true;
          weight[v] = weight[v] > 0.3 ? 0.5 * weight[v] : 0.0;
          changed = true;
        }
      }
    }
    if (!changed) break;  // every crossing face is flat already: the TIN itself crosses
    ++repair.rounds;
    for (size_t p = 0; p < n; ++p) {
      const auto& fv = face_vertices[tess->point_face[p]];
      const Eigen::Vector3d& b = tess->point_barycentric[p];
      const double w = b[0] * weight[fv[0]] + b[1] * weight[fv[1]] + b[2] * weight[fv[2]];
      if (w < 1.0) tess->points[p] = chord[p] + w * offset[p];
    }
  }
  repair.faces_changed = static_cast<int>(
      std::count_if(face_vertices.begin(), face_vertices.end(), [&](const std::array<int, 3>& fv) {
        return weight[fv[0]] < 1.0 || weight[fv[1]] < 1.0 || weight[fv[2]] < 1.0;
      }));
  repair.vertices_weighted = static_cast<int>(
      std::count_if(weight.begin(), weight.end(), [](double w) { return w < 1.0; }));
  for (size_t p = 0; p < n; ++p) {
    repair.max_move = std::max(repair.max_move, (tess->points[p] - (chord[p] + offset[p])).norm());
  }
  return repair;
}

}  // namespace facets
