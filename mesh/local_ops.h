// Local topological operations on the TIN (DESIGN.md section 3): edge split, edge flip
// by the Delaunay criterion in the local tangent plane, vertex removal, tangential
// Laplacian smoothing and the quality pass that keeps the point density homogeneous.
// None of them re-triangulates globally.
#pragma once

#include <array>
#include <vector>

#include "mesh/tin.h"

namespace facets {

// Splits edge eh at the midpoint of its G1 boundary curve (not the chord midpoint);
// the new vertex's normal is the G1 surface normal there, so the surface barely
// changes. The two (or one, on the boundary) adjacent triangles become four (two).
TinMesh::VertexHandle SplitEdge(TinMesh* mesh, TinMesh::EdgeHandle eh);

// Tangent plane of edge (a, b) with opposite vertices c, d: normal = normalised mean of
// the four vertex normals (symmetric in the quad, so an edge and its flip are judged
// in the same plane and flips cannot cycle). The four vertices are projected onto it;
// the edge is Delaunay when the two angles opposite it sum to at most pi
// (+ tolerance). Boundary edges are.
bool IsTangentDelaunay(const TinMesh& mesh, TinMesh::EdgeHandle eh, double tolerance = 1e-9);
// True when flipping eh is topologically allowed and the flipped pair is not folded in
// the edge's tangent plane (both new triangles positively oriented).
bool CanFlip(const TinMesh& mesh, TinMesh::EdgeHandle eh);
// Flips every non-Delaunay edge that CanFlip until all are Delaunay (edge queue; at most
// max_flips flips, 0 = 10 * number of edges). Returns the number of flips.
int MakeTangentDelaunay(TinMesh* mesh, int max_flips = 0);
// The same over the edges whose two ends are flagged in `within` (one flag per vertex):
// the rest of the TIN keeps its edges, Delaunay or not.
int MakeTangentDelaunayWithin(TinMesh* mesh, const std::vector<bool>& within);

// Vertices of `mesh` whose surroundings differ from `before` (an earlier state of the same
// TIN, vertices and faces only appended since, none deleted): moved, inserted, or a
// corner of a face that is new or whose corners changed (a split or a flip).
std::vector<bool> VerticesChangedFrom(const TinMesh& mesh, const TinMesh& before);

// Removes vertex vh by collapsing its shortest collapsible outgoing edge into the
// neighbour, then restores tangent-plane Delaunay around that neighbour. Calls
// garbage_collection(): all handles and indices are invalidated. Returns false (and
// leaves the mesh unchanged) when no collapse is topologically allowed.
bool RemoveVertex(TinMesh* mesh, TinMesh::VertexHandle vh);

struct SmoothingOptions {
  int iterations = 1;
  // Fraction of the way to the neighbours' centroid (tangential part) per iteration;
  // at most 0.5 so a vertex never jumps over its one-ring.
  double step = 0.5;
  // Boundary vertices stay where they are (a 2.5D start grid's rim defines the ROI).
  bool fix_boundary = true;
  // true: the moved vertex is put back onto the G1 surface of the previous iteration
  // (located in the adjacent face whose tangent-plane projection contains it), with
  // that surface's normal, so smoothing does not change the shape beyond the
  // interpolation error. false: the vertex stays in its tangent plane.
  bool stay_on_surface = true;
  // Below 180: creases are detected with this angle (mesh/creases.h) before every
  // iteration; the surface moved on is the G1 surface with those creases, and crease
  // vertices stay where they are, so smoothing does not round ridges, eaves and the
  // feet of walls. 180: the plain G1 surface through the vertex normals.
  double crease_angle_deg = 180.0;
  bool rounded_ridges = false;
  void Check() const;
};
struct SmoothingReport {
  int moved = 0;             // vertex moves summed over iterations
  double max_move = 0.0;     // largest single move
  int off_surface = 0;       // moves that could not be located in a face
  int crease_vertices = 0;   // vertices held on creases (last iteration)
};
SmoothingReport TangentialSmooth(TinMesh* mesh, const SmoothingOptions& options = {});

struct QualityOptions {
  // Target edge length of this level (the engine derives it from the grey-facet size).
  double target_edge_length = 1.0;
  // Edges longer than this factor times the target are split; 1.5 keeps the halves
  // (0.75 target or more) from getting too short.
  double split_factor = 1.5;
  // Rounds of splitting; each round halves the longest edges.
  int max_rounds = 20;
  // When set (one flag per vertex): only edges with a flagged end are split (a vertex
  // inserted between two flagged ones counts as flagged in the next round), and only
  // edges between flagged or inserted vertices are flipped (MakeTangentDelaunayWithin).
  const std::vector<bool>* near = nullptr;
  void Check() const;
};
struct QualityReport {
  int splits = 0;
  int flips = 0;
  double max_edge_length = 0.0;  // after the pass
};
// Splits edges that grew too long (walls standing up out of a 2.5D start) at their G1
// midpoints, then flips to restore tangent-plane Delaunay. Vertex normals of old
// vertices are kept; face normals updated.
QualityReport QualityPass(TinMesh* mesh, const QualityOptions& options);
// Edges QualityPass would split in its first round (longer than split_factor x
// target_edge_length, with a flagged end when `near` is set).
int CountLongEdges(const TinMesh& mesh, const QualityOptions& options);

// Vertices no image saw (views[v] == 0: hidden under a roof that rose over them, or
// behind a wall) have no observation to pull them anywhere, and at creases no curvature
// pseudo-observation either: a sheet of them stays folded under the roof. Each such
// vertex moves to the mean of its neighbours (Jacobi, `iterations` times) while seen
// and boundary vertices stay: the hidden part becomes the membrane spanned by the seen
// surface around it. Vertex normals are not updated. Returns the vertices relaxed.
int RelaxUnseenVertices(TinMesh* mesh, const std::vector<int>& views, int iterations = 100);

// A triangle of this doubled area and longest edge has no area to speak of: its least
// height is below relative_height x the longest edge.
bool NoArea(double twice_area, double longest, double relative_height);
// The face's halfedges ordered by length: [0] shortest, [2] longest; whether the face has
// no area (NoArea).
bool DegenerateFace(const TinMesh& mesh, TinMesh::FaceHandle f, double relative_height,
                    std::array<TinMesh::HalfedgeHandle, 3>* by_length);
// Faces with no area (DegenerateFace).
int CountDegenerate(const TinMesh& mesh, double relative_height);

// Triangles of (nearly) no area in a mesh from elsewhere (a start mesh from another
// program, points snapped onto one line): the G1 patch of such a triangle divides by
// its zero area, so a split or a tessellation there is not finite. A triangle is
// degenerate when its least height is below relative_height x its longest edge. A
// needle (its shortest edge below relative_height x its longest: two points on top of
// each other) loses that edge by a collapse; a cap (one vertex on the opposite edge)
// has that edge flipped, or, where it cannot be (the boundary, or the vertex across on
// the line too), its vertex collapsed into the nearer end of that edge. Repeated until
// none is left or nothing more can be done. When it found any: garbage_collection()
// (handles and indices invalidated), face and vertex normals updated.
struct DegenerateRepairReport {
  int degenerate = 0;  // degenerate triangles found before the repair
  int collapsed = 0;
  int flipped = 0;
  int left = 0;        // degenerate triangles after the repair
};
DegenerateRepairReport RepairDegenerateTriangles(TinMesh* mesh, double relative_height = 1e-6);

// Mean over faces of the smallest angle (radians), and the smallest over all faces.
struct AngleStats {
  double min_angle = 0.0;
  double mean_min_angle = 0.0;
};
AngleStats FaceAngleStats(const TinMesh& mesh);

}  // namespace facets
