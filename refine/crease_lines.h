// Crease lines straightened: chains of vertices put onto the line where two planes meet.
//
// A building-refinement heuristic on the surface model: roof ridges, hips, valleys,
// eaves and wall feet are straight lines, but a TIN whose grid runs skew to them holds
// them only as zigzags of crease edges (mesh/creases.h detects those).
#pragma once

#include <vector>

#include "mesh/tin.h"

namespace facets {

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
  double max_move = 0.0;  // m, the largest distance a vertex moved
  // Why the other sets and runs were left (each counts once, at its first failing test):
  int sets = 0;               // connected sets of crease vertices
  int lines = 0;              // straight runs cut from them (candidate lines)
  int too_small = 0;          // sets of fewer than min_edges crease edges, or runs with under 3 vertices near their line
  int too_short = 0;          // runs whose line spans fewer than min_edges edges
  int sides_not_planar = 0;   // the surface 1-3 edges away on a side is not a plane (or too few vertices)
  int sides_not_meeting = 0;  // side planes under 10 degrees apart, over 20 degrees off the line, or over an edge away
  int no_chain = 0;           // no vertex chain to follow along the line
};
StraightenReport StraightenCreaseChains(TinMesh* mesh, const std::vector<bool>& crease_edge,
                                        int min_edges = 3,
                                        double max_offset = 0.75);

}  // namespace facets
