// Which images of a block to hold out: the images `facets reconstruct --exclude-images`
// leaves out and `facets evaluate --holdout --holdout-images` predicts, named by one
// shared syntax so the two line up.
//
// SPEC is one of
//   every-5th      every Nth image (N >= 2; "every-5" is the same): with the block's
//                  images sorted by name, positions N-1, 2N-1, ... (0-based), i.e. the
//                  5th, 10th, 15th, ... file. Sorting by name makes the choice depend on
//                  the image files only, not on the order of the model's images.txt.
//   a.jpg,b.jpg    image names as in the model (BlockImage::name), comma-separated
//   FILE           an existing text file: one image name per line; blank lines and
//                  lines starting with '#' are skipped
// An unknown name is an error naming it (and the file it came from).
#pragma once

#include <string>
#include <vector>

#include "io/image_block.h"

namespace facets {

// The held-out default of `facets evaluate --holdout`.
inline constexpr const char* kDefaultHoldoutSpec = "every-5th";

// Indices into block.images of the images SPEC names, ascending, without repeats.
// Throws std::invalid_argument naming the spec, the file or the unknown image.
std::vector<int> SelectImages(const ImageBlock& block, const std::string& spec);

// The block without the images at `indices`: their tie-point observations are dropped,
// and tie points then seen by fewer than two images are dropped too (a point needs two
// rays). Cameras stay (unused ones are harmless).
ImageBlock WithoutImages(const ImageBlock& block, const std::vector<int>& indices);

// "a.jpg, b.jpg" for messages.
std::string ImageNames(const ImageBlock& block, const std::vector<int>& indices);

}  // namespace facets
