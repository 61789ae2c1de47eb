// Crease edges and corner normals: where the G1 surface must not round a sharp edge.
//
// Built-up areas are full of creases (roof ridges, eaves, wall-roof and wall-ground
// edges). A G1 surface through vertex normals averaged across such an edge rounds it
// over a whole triangle on each side (a 20-degree gable roof on 2 m triangles bulges
// by about 0.1 m), and the adjustment then pulls the crease vertices away from the
// true edge to compensate. So: an interior edge whose two face normals differ by more
// than a crease angle is a crease edge; around a vertex on creases, the faces fall
// into sectors separated by crease edges, and each face's patch uses its sector's
// normal at that corner (the angle-weighted mean of the sector's face normals, made
// orthogonal to the bounding crease edges). The boundary curve of a crease edge is the
// straight chord for both faces (G1Patch with straight edges): the surface stays
// continuous (G0) across creases, G1 across every other edge, and planar roof faces
// are reproduced exactly.
//
// The vertex normals (displacement directions of the adjustment) are not changed.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "mesh/g1_patch.h"
#include "mesh/tin.h"

namespace facets {

struct CornerNormals {
  // Normal at the to-vertex of each halfedge for the face of that halfedge, indexed by
  // halfedge index (entries of boundary halfedges are unused).
  std::vector<Eigen::Vector3d> normals;
  // Sector of that corner at its vertex: 0 .. vertex_sectors[v]-1 (0 off creases).
  std::vector<int> corner_sector;
  std::vector<int> vertex_sectors;  // by vertex index, >= 1
  std::vector<bool> crease_edge;    // by edge index
  int num_crease_edges = 0;
  int num_crease_vertices = 0;
};

// Interior edges whose adjacent unit face normals enclose more than crease_angle_deg
// (>= 180: none), and with rounded_ridges the ridge row of a crease rounded over a band of edge rows: an
// edge bent by at least half the angle, whose opposite corners' vertex normals enclose
// more than the angle, and that bends most among the roughly parallel edges at those
// corners (curvature regularisation keeps a ridge round until it is declared a crease).
std::vector<bool> DetectCreaseEdges(const TinMesh& mesh, double crease_angle_deg, bool rounded_ridges = false);

// Which straight runs StraightenCreaseChains takes, by the planes that meet on them
// (+Z up, as in aerial scenes; closed starts do not straighten): roof lines (ridges,
// hips, valleys: both planes within kSteepCreaseSideDeg of horizontal) or steep lines
// (eaves and feet, where a wall meets a roof or the ground). With
// ReconstructionOptions::straighten_by_kind the engine straightens the two kinds in
// rounds of their own, each kept only when it fits better: a round of all lines on the
// block was dropped for the eaves of crumpled walls, and the ridges it would have set
// right went with them (issue 7).
enum class CreaseLines { kAll, kRoof, kSteep };
constexpr double kSteepCreaseSideDeg = 60.0;

// A ridge skew to the grid of a TIN becomes a zigzag of crease edges: the vertices can
// only move along their normals, so none lies on the ridge, and the crease vertices
// (free of curvature regularisation) spike to fit it. This puts chains of vertices on
// the line of their crease. Each connected set of crease edges (at least min_edges of
// them) is cut into straight runs first (a building's eaves, ridges and hip lines join
// into one web): lines through pairs of its vertices, the one with most vertices within
// max_offset edges in one stretch taken out, until no stretch spans min_edges edges. For
// each run: a least-squares line through its vertices (those farther than max_offset
// edge lengths dropped, twice), spanning at least min_edges edges; the crease line
// proper is where the planes fitted to the surface 1-3 edges away on either side (and
// within 4.5 edges of the line) meet
// (a zigzag's vertices lie mostly on one side of the true crease; a run cut from a web
// only its middle, an edge short of each end, where no other crease's faces are); both
// sides planar (rms within a tenth of an edge once points beyond twice the rms are
// dropped, keeping three quarters), meeting at 10 degrees or more, within 20 degrees of
// and one edge from the first line, else the run is left. The chain is followed
// through the mesh from the vertex nearest the line in the middle to both ends (one and
// a half edges beyond the crease vertices; for a run cut from a web half an edge short
// of its ends, leaving the junction), each step to the neighbour that advances
// along the line by at least a third of an edge and lies closest to it, within
// max_offset edges; its vertices go onto the line, a border vertex by sliding along a
// straight stretch of the border to where the line crosses it. A face whose
// three corners all went onto the line (the chain zigzags through it) has its long
// edge flipped to the vertex across it (the vertex and face counts stay; the flipped
// faces' indices are those of the two faces before). When a face would fold (turn by more
// than 60 degrees) or a cap cannot be flipped, the corner of that face that moved most stays
// where it was and the run is tried again; the run is left when a third of its chain would stay.
// Vertex normals are updated when anything moved.
struct StraightenReport {
  int components = 0;  // straight crease lines found
  int moved = 0;       // vertices put on their line
  int rejected = 0;    // components left because a face would fold (or a cap could not be flipped)
                       // with a third of their chain already left off
  int left_off = 0;    // chain vertices of taken lines kept where they were, so that no face folds
  int flipped = 0;     // faces with no area (all three corners on the line) whose long edge was flipped
  double max_move = 0.0;
  // Why the other sets and runs were left (each counts once, at its first failing test):
  int sets = 0;               // connected sets of crease vertices
  int lines = 0;              // straight runs cut from them (candidate lines)
  int too_small = 0;          // sets of fewer than min_edges crease edges, or runs with under 3 vertices near their line
  int too_short = 0;          // runs whose line spans fewer than min_edges edges
  int sides_not_planar = 0;   // the surface 1-3 edges away on a side is not a plane (or too few vertices)
  int sides_not_meeting = 0;  // side planes under 10 degrees apart, over 20 degrees off the line, or over an edge away
  int no_chain = 0;           // no vertex chain to follow along the line
  int other_kind = 0;         // runs of the kind of line not asked for (CreaseLines)
};
StraightenReport StraightenCreaseChains(TinMesh* mesh, const std::vector<bool>& crease_edge,
                                        CreaseLines lines = CreaseLines::kAll, int min_edges = 3,
                                        double max_offset = 0.75);

// Corner normals for a given set of crease edges (kept fixed while a window is
// adjusted, so that the grey lattice keeps its node indices). Vertex normals must be
// up to date (UpdateVertexNormals).
CornerNormals ComputeCornerNormals(const TinMesh& mesh, const std::vector<bool>& crease_edge);
inline CornerNormals ComputeCornerNormals(const TinMesh& mesh, double crease_angle_deg, bool rounded_ridges = false) {
  return ComputeCornerNormals(mesh, DetectCreaseEdges(mesh, crease_angle_deg, rounded_ridges));
}

// Patches with corner normals (compare FacePatch / BuildPatches of mesh/tin.h, which
// use the vertex normals).
G1Patch FacePatch(const TinMesh& mesh, TinMesh::FaceHandle fh, const CornerNormals& corners);
std::vector<G1Patch> BuildPatches(const TinMesh& mesh, const CornerNormals& corners);

}  // namespace facets
