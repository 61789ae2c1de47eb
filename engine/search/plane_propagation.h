// Plane propagation between pyramid levels: a wall that a coarse level put
// partly right and partly 1-2 m off (the tall building's east wall in the block: the
// upper half on the wall, the lower half in front of it with a ledge between) is beyond
// the reach of the search along each vertex's own normal (engine/search/normal_search.h) and of
// least-squares matching. Its good part, though, already lies on the right plane. As in
// PatchMatch stereo, every vertex tries the planes of its neighbours whose images agree
// well there (a neighbour's tangent plane, or a face whose three corners agree): it goes
// onto such a plane (orthogonal projection), a patch in that plane is scored by the mean
// pairwise NCC of the images that see it, and the best plane that beats the vertex's own
// patch by a clear gain is taken. A vertex looks again when a neighbour changed, so good
// planes spread about a ring per iteration: along a wall from its good part, and from
// roof and ground into the rounded eaves and feet a coarse level leaves. A vertex's own
// score does not decide whether it borrows: a patch a metre off a smooth texture can
// still correlate well (the seed gable at four pixels below: 0.6 and more). Folding
// steps are halved or undone (mesh/surface_validity.h).
#pragma once

#include <vector>

#include "engine/images/level_image.h"
#include "mesh/tin.h"

namespace facets {

struct PlanePropagationOptions {
  int iterations = 8;             // each carries the planes about one ring further
  double max_move_pixels = 16.0;  // onto a plane at most this far (level ground pixels)
  // A vertex lends its plane when its images agree there at least this well (mean
  // pairwise NCC of its patch in its tangent plane, or of the borrowed plane's patch).
  double source_score = 0.6;
  double min_score = 0.4;   // a borrowed plane must score at least this
  double min_gain = 0.1;    // and this much above the vertex's own score
  // Only vertices whose normal turns at least this far from vertical borrow (walls and
  // the ramps of rounded eaves and feet, not roofs and ground; 0 = every vertex).
  double min_target_tilt_deg = 0.0;
  int patch_half = 4;       // patch of (2 * patch_half + 1)^2 samples
  double sample_pixels = 1.0;  // sample spacing in the patch, level ground pixels
  // A borrowed plane is scored in the images whose rays reach it with no surface in the
  // way nearer than this (level ground pixels; at least the move, plus the patch's
  // radius): the surface the vertex leaves stands in front of the plane it tries (a
  // wall's lower half 1-3 m out with a ledge above hides the true wall from the nadir
  // images).
  double occluder_slack_pixels = 0.0;
  double min_cos = 0.2;     // an image sees a plane at |cos| >= this
  int min_images = 2;
  double min_contrast = 2.0;  // grey-value standard deviation of a patch in an image
};

struct PlanePropagationReport {
  int sources = 0;       // vertices lending their plane at the start (score >= source_score)
  int targets = 0;       // vertices that may borrow (not on the boundary, tilted enough)
  int hypotheses = 0;    // planes scored
  int moved = 0;         // vertices on a borrowed plane after the fold guard
  int limited = 0;       // moves the fold guard halved or undid
  int iterations = 0;    // iterations that moved some vertex
  double median_move = 0.0;  // m
  double max_move = 0.0;
};

// `ground_pixel`: the level's ground pixel (m). Boundary vertices stay. Vertex normals
// are updated afterwards.
PlanePropagationReport PropagatePlanes(TinMesh* mesh, const std::vector<LevelImage>& images, double ground_pixel,
                                       const PlanePropagationOptions& options);

}  // namespace facets
