// Windows of a TIN (DESIGN.md section 2, "Windows"): a level's surface is adjusted in
// overlapping windows of a few hundred geometry triangles, so the cost of one
// adjustment (and its memory) is bounded by the window, not by the scene.
//
// A window is a set of core faces (the faces whose vertices it estimates) plus a
// margin of face rings around them. The margin gives the core vertices complete
// 1-rings and curvature stencils; its outermost vertices (those with a face outside
// the window) are held fixed at their neighbours' current values. Every vertex belongs
// to the core of exactly one window, which writes its result back ("only interiors
// kept").
#pragma once

#include <vector>

#include "mesh/tin.h"

namespace facets {

struct WindowPartitionOptions {
  // Most core faces per window; a mesh with at most this many faces is one window.
  int max_faces = 400;
  // Face rings around the core (>= 1: core vertices need their whole 1-ring).
  int margin_rings = 2;
  void Check() const;  // throws std::invalid_argument naming the bad field
};

struct MeshWindow {
  std::vector<int> core_faces;      // ascending
  std::vector<int> faces;           // core + margin, ascending
  std::vector<int> owned_vertices;  // ascending: the vertices whose result this window keeps
};

// Splits the faces into windows by recursive halving at the median face centre along
// the longest axis of the centres' bounding box (a balanced octree-like subdivision:
// median splits keep the windows equally large where the surface is uneven, e.g. a
// facade beside a roof). Deterministic. The mesh must have no deleted elements.
std::vector<MeshWindow> PartitionIntoWindows(const TinMesh& mesh,
                                             const WindowPartitionOptions& options);

// Same over a subset of the faces (a local re-adjustment around vertices that moved):
// only those faces are cores; margins grow into the rest of the mesh; a vertex belongs
// to the window of its lowest-index face in the subset, vertices without one to none.
std::vector<MeshWindow> PartitionFacesIntoWindows(const TinMesh& mesh, std::vector<int> faces,
                                                  const WindowPartitionOptions& options);

// Faces with a corner within `rings` edge rings of a vertex marked in `seeds` (0: the
// faces around the marked vertices): what a local re-adjustment covers.
std::vector<int> FacesNearVertices(const TinMesh& mesh, const std::vector<char>& seeds, int rings);

// Groups of windows that share no vertex (not even fixed margin vertices): the windows
// of one group read and write disjoint parts of the mesh and may run in parallel;
// groups run one after the other. Greedy colouring in window order; deterministic.
std::vector<std::vector<int>> IndependentWindowGroups(const TinMesh& mesh,
                                                      const std::vector<MeshWindow>& windows);

// A window as a mesh of its own, for the adjustment.
struct WindowMesh {
  TinMesh mesh;                     // the window's faces, same orientation and normals
  std::vector<int> global_vertex;   // window vertex -> mesh vertex
  std::vector<int> global_face;     // window face -> mesh face (= MeshWindow::faces order)
  std::vector<bool> fixed;          // window vertex has a face outside the window
  std::vector<int> owned_local;     // window vertices of MeshWindow::owned_vertices
};

// Copies the window's faces (vertex order kept) with points and vertex normals as they
// are in `mesh`. Throws std::runtime_error when OpenMesh refuses a face (a window whose
// faces would make a non-manifold vertex).
WindowMesh ExtractWindowMesh(const TinMesh& mesh, const MeshWindow& window);

}  // namespace facets
