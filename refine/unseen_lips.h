// Unseen lips: sheets of the surface that left a wall's top as a lip and came back
// under themselves to the wall further down.
//
// On the block's tall building (thorough run) the surface leaves the roof edge as a lip
// up to 3 m in front of the east wall and folds back to the wall at mid height. The
// lip's top fits the images on that side well enough (a point 2 m in front of a
// textured wall projects to nearly the same texture in images looking at it), its
// underside faces down and no image sees it, and nothing in the adjustment pulls it
// back: the regularisation keeps it smooth and steps along the normals keep it a lip.
// It carried 68 % of the squared wall error. The truth of a built-up area has no
// surface facing down that no image sees, only overhangs seen from below by obliques.
//
// The same holds for a pocket: a sheet that goes into the building behind a seen wall
// (e.g. ground running 1-1.5 m under the wall, the wall standing up behind its true place
// and coming back at mid height), seen by no image because its own rims hide it.
//
// The operation: groups of unseen steep or down-facing vertices beside a wall seen by
// two or more images; the wall's plane fitted to the seen steep vertices around the
// group that face the same way; the lip = the group and the vertices connected to it
// in front of that plane (or, for a pocket, behind it and seen by fewer than two
// images); its vertices laid onto the plane by a Tutte embedding in the plane's
// coordinates, with the vertices around the lip held at their projections, so the
// laid-down sheet does not fold over itself. The caller re-adjusts the windows around
// each lip and keeps it only when the images agree (engine/reconstruction.cc).
#pragma once

#include <Eigen/Core>
#include <vector>

#include "mesh/tin.h"

namespace facets {

struct LipFoldOptions {
  // A vertex is part of the lip while it stands more than this in front of (or behind)
  // the wall plane (m); the caller uses a share of the level's edge length.
  double front_tolerance = 0.05;
  // The wall's plane must fit its vertices to within this rms (m) after the outliers'
  // cut, else the group is left (no_wall).
  double max_plane_rms = 0.1;
  // Unseen vertices whose normal's z is below this are steep or face down (a lip's
  // underside, a pocket's sides); unseen roofs and ground face up and are left to the
  // relaxation.
  double max_normal_z = 0.35;
  int min_group = 3;               // fewer unseen vertices: left alone
  double min_horizontal = 0.2;     // the group's mean normal must lean out this much
  int wall_rings = 4;              // wall vertices searched within this many edge rings
  int min_wall_vertices = 6;
  int wall_min_views = 2;          // wall vertices: seen by at least this many images
  double wall_max_normal_z = 0.35;  // steep: |normal z| at most this (plane too)
  double wall_min_facing = 0.5;     // cos of the angle between their horizontal normal and the group's
  // The lip reaches at most this times the group's farthest point from the plane.
  double reach_factor = 1.5;
  int max_lip = 2000;              // larger: not a lip (left alone, not_free)
  int embedding_iterations = 2000;
};

// One lip found: its vertices and the plane of the wall it is laid onto.
struct UnseenLip {
  std::vector<int> vertices;
  int in_front = 0;  // of them, in front of the wall (the others behind it: a pocket)
  Eigen::Vector3d plane_point = Eigen::Vector3d::Zero();
  Eigen::Vector3d plane_normal = Eigen::Vector3d::UnitX();  // pointing out of the wall
  int support = 0;          // seen wall vertices the plane was fitted to (after the cut)
  double plane_rms = 0.0;   // their rms distance from it (m)
};

struct LipSearch {
  std::vector<UnseenLip> lips;  // disjoint
  int groups = 0;    // groups of unseen steep or down-facing vertices (>= min_group)
  int no_wall = 0;   // groups without a planar seen wall beside them
  int not_free = 0;  // lips that reached the TIN's border or grew beyond max_lip
};

// Groups of at least min_group connected unseen vertices (views 0, not on the border)
// whose normals are steep or face down and whose mean normal leans out; for each, the
// plane of the seen wall it hangs from: the vertices within wall_rings rings seen by
// wall_min_views or more images, steep and facing the same way, at least
// min_wall_vertices; a total-least-squares plane through them, refitted three times
// without the points beyond three robust sigmas (MAD), within max_plane_rms. The lip:
// the group's vertices more than front_tolerance from the plane and the vertices
// connected to them on the same side: in front, any vertex not below the group's
// lowest (the lip's seen top belongs to it, the ground in front does not); behind (a
// pocket into the building), vertices seen by fewer than wall_min_views images only
// (the roof behind the wall is seen); on both sides at most reach_factor times the
// group's farthest vertex from the plane. A lip reaching the border or growing beyond
// max_lip is left (not_free). views: images seeing each vertex (VisibleViews), by
// vertex index; vertex normals must be set.
LipSearch FindUnseenLips(const TinMesh& mesh, const std::vector<int>& views, const LipFoldOptions& options);

struct LipFold {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();  // mean of the lip's vertices before
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();  // the wall plane's, pointing out of the wall
  int support = 0;
  double plane_rms = 0.0;
  int vertices = 0;
  int in_front = 0;
  double max_move = 0.0;  // m
};

// Lays the lip onto its plane: Tutte's embedding (each vertex at the mean of its
// neighbours, Jacobi, at most `iterations` sweeps) in the plane's coordinates, with the
// vertices around the lip held at their projections, so the laid-down sheet does not
// fold over itself. Only the lip's vertices move; vertex normals are not updated.
LipFold LayLipOntoWall(TinMesh* mesh, const UnseenLip& lip, int iterations = 2000);

// A laid lip whose sheet meets the held wall at a small crumple folds a face or two
// there (the held ring is where the images put it, a few cm off the fitted plane: a 5 m
// lip of 146 vertices can be left for 1-2 such faces). The corners
// of faces folded now but not in folded_before (FoldedFaces, by face index) that are
// not the lip's and lie within reach of the wall plane (the caller: the lip's front
// tolerance, within which a vertex counts as the wall's) are projected onto it; up to
// `rounds` times while any moves. Returns the vertices projected; vertex normals are
// not updated.
int FlattenFoldedRim(TinMesh* mesh, const UnseenLip& lip, const std::vector<bool>& folded_before, double reach,
                     int rounds = 3);

// Both, every lip found laid down (the engine lays and judges them one at a time).
struct LipFoldReport {
  std::vector<LipFold> lips;
  int groups = 0;
  int folded = 0;
  int moved = 0;
  double max_move = 0.0;
  int no_wall = 0;
  int not_free = 0;
};
LipFoldReport FoldUnseenLipsOntoWalls(TinMesh* mesh, const std::vector<int>& views,
                                      const LipFoldOptions& options);

}  // namespace facets
