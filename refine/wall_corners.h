// Vertical corners where two planar walls meet, and optionally wall feet and eaves.
//
// The adjusted walls of a thorough run are flat and in place, but a TIN from a 2.5D
// start puts no vertex on a building's vertical corner: the faces between the last
// vertices of one wall and the first of the next cut the corner off (0.6-0.9 m inside
// a 12 m building's corners on block_oblique), and in a band about a metre wide the
// faces crumple: there 5 % of the wall samples, those within 3 ground pixels of a
// corner, carried 26-37 % of the walls' squared distance.
//
// FindWallCorners grows the faces into planar regions: a face joins across an edge
// when its normal is within region_angle_deg of its neighbour's and of the region's
// and its corners lie within region_tolerance edge lengths of the region's plane
// (flattest faces seed first; the plane refitted as the region doubles); regions of at
// least min_region_faces faces whose total-least-squares plane fits within the
// tolerance are kept. A wall grown in pieces (its faces crumpled near a corner, a lower
// band a few degrees off) is put together again: steep regions whose vertices come
// within one edge of each other merge when their normals lie within region_angle_deg
// and one plane fits both within the tolerance (merge_wall_pieces). Two steep regions
// (normals more than 60 degrees from +Z) whose normals enclose 45-135 degrees make a corner where their planes meet when both come
// within 1.6 edges of that line and run beside it together over at least two edges
// (the corner spans that common stretch, half an edge short of each end, so the eave
// and the foot stay as they are). Its band: the vertices within `band` edges of the
// line there, not on the border and not on a roof or ground region (a face of theirs
// in a region less steep).
//
// Optionally (feet, eaves) the same for a wall and a gentle region (normal within 60
// degrees of +Z) meeting it: a re-entrant crease is a foot (the ground, or a lower roof,
// at the bottom of a wall), a convex one an eave. Their planes are refitted to the
// region's vertices within local_fit edges of the line (the ground around a building is
// one wavy region; its global plane is not the one at the wall), and their band leaves
// out vertices on any third region.
//
// LayCornerOntoWalls moves each band vertex onto the wall it is nearer to (a convex
// corner: the plane it is least inside of; a re-entrant one: the plane it is least
// outside of), and onto the corner line when it would then still stand outside the
// other wall (inside, for a re-entrant corner) or lies within `snap` edges of the line,
// so that the corner gets a chain of vertices of its own. Where that turns a face's back
// on the walls (its normal against their mean, or against its neighbours') or leaves it
// without area (least height under 5 % of its longest edge), the face's corner that moved
// most goes back, until no such face is left. The caller judges the result
// (crossings, folds, the images) and restores the mesh when it is worse. Vertex normals
// are not updated.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "mesh/tin.h"

namespace facets {

enum class CreaseKind { kVertical, kFoot, kEave };
const char* CreaseName(CreaseKind kind);  // "corner", "foot", "eave"

struct WallCornerOptions {
  double edge_length = 1.0;        // the level's target edge length (h)
  double region_angle_deg = 12.0;  // face to face and face to region normal
  double region_tolerance = 0.1;   // corners within this many h of the region's plane
  int min_region_faces = 6;
  double band = 1.5;  // vertices within this many h of the corner line are laid onto the walls
  double snap = 0.6;  // ... and onto the line itself within this many h of it
  bool vertical = true;    // two walls
  // Least angle between two walls' normals for a vertical corner (feet and eaves: 45).
  // A one-face chamfer cut across a right-angled corner encloses about 45 degrees with
  // each wall (a false corner at 48 degrees was seen); 60 leaves it out, and a
  // building's corners are far steeper.
  double min_corner_angle_deg = 60.0;
  // Steep regions within an edge of each other that one plane fits merged into one wall
  // before the pairs are formed (a wall grown in pieces near a corner).
  bool merge_wall_pieces = true;
  bool feet = false;       // a wall and the gentle region at its foot (re-entrant)
  bool eaves = false;      // a wall and the roof on top of it (convex)
  double local_fit = 3.0;  // feet and eaves: planes refitted within this many h of the line
  void Check() const;  // throws std::invalid_argument naming the bad field
};

struct WallCorner {
  Eigen::Vector3d point = Eigen::Vector3d::Zero();      // on the corner line, middle of its stretch
  Eigen::Vector3d direction = Eigen::Vector3d::UnitZ();  // unit, along the line
  double half_length = 0.0;                              // of the stretch along it
  Eigen::Vector3d normal[2], centre[2];                  // the two walls' planes (normals outward)
  bool convex = true;
  CreaseKind kind = CreaseKind::kVertical;
  std::vector<int> band;  // vertex indices
  double angle_deg() const;  // between the two planes' normals (90: a right-angled crease)
};

struct WallCornerSearch {
  std::vector<WallCorner> corners;
  int regions = 0;       // planar regions
  int wall_regions = 0;  // of them steep
  int merged_walls = 0;  // wall pieces merged into another (merge_wall_pieces)
  int count(CreaseKind kind) const;
};

WallCornerSearch FindWallCorners(const TinMesh& mesh, const WallCornerOptions& options);

struct CornerLaying {
  int moved = 0;    // band vertices moved
  int on_line = 0;  // of them onto the corner line
  int left_off = 0;  // put back: a face of theirs would have turned its back or lost its area
  double max_move = 0.0;
};
CornerLaying LayCornerOntoWalls(TinMesh* mesh, const WallCorner& corner, const WallCornerOptions& options);

}  // namespace facets
