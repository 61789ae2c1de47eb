// Search along the vertex normals between pyramid levels: a coarse level that put a wall
// or an eave 1-2.5 m off leaves it 4-10 pixels off on the next level, beyond the pull-in
// of least-squares matching. Before such a level is adjusted, every vertex tries offsets
// along its normal over a range of level pixels: a small patch in its tangent plane is
// projected into the images that see it and scored by the mean pairwise normalised
// cross-correlation of their grey values (object lifting of seed 001, done per vertex
// and along the normal). Vertices with a clear, better peak move there; the moves are
// median-filtered over neighbours facing the same way (a single false match does not
// survive), and steps that fold the surface are halved or undone
// (mesh/surface_validity.h). The adjustment then starts within its pull-in.
#pragma once

#include <vector>

#include "engine/images/level_image.h"
#include "mesh/tin.h"

namespace facets {

struct NormalSearchOptions {
  double range_pixels = 8.0;  // offsets over +- this many level ground pixels
  double step_pixels = 0.5;   // offset step, level ground pixels
  int patch_half = 4;         // patch of (2 * patch_half + 1)^2 samples
  double sample_pixels = 1.0;  // sample spacing in the tangent plane, level ground pixels
  double min_cos = 0.2;       // an image sees the vertex's plane at |cos| >= this
  int min_images = 2;
  double min_contrast = 2.0;  // grey-value standard deviation of a patch in an image
  // Least mean pairwise NCC of the best offset (-1..1): higher takes fewer walls back,
  // lower takes false peaks on roofs (the block's roofs 0.20 GSD off at 0.3 against 0.15
  // at 0.4).
  double min_score = 0.4;
  double min_gain = 0.1;      // over the score where the vertex is
  // Only vertices whose normal turns more than this from the mean direction to the images
  // that see them, degrees (walls of an aerial block, not its roofs and ground; 0 = every
  // vertex, which lets look-alike peaks move roofs and terrain).
  double min_angle_to_views_deg = 45.0;
  double neighbour_cos = 0.8;  // neighbours that vote face within ~37 deg
};

struct NormalSearchReport {
  int searched = 0;  // vertices with >= min_images images
  int peaks = 0;     // of them with an accepted peak off zero
  int moved = 0;     // moved after the median filter (|move| >= a tenth of a step)
  int limited = 0;   // moves the fold guard halved or undid
  double median_move = 0.0;  // |move| of the moved vertices (m)
  double max_move = 0.0;
};

// `ground_pixel`: the level's ground pixel (m), which scales the range, step and patch.
// The vertical is the local Z axis (aerial blocks). Boundary vertices stay. Vertex normals are updated afterwards.
NormalSearchReport SearchAlongNormals(TinMesh* mesh, const std::vector<LevelImage>& images,
                                      double ground_pixel, const NormalSearchOptions& options);

}  // namespace facets
