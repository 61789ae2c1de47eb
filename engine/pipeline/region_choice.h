// The region of interest of a run: given, the block's, or chosen from the tie points
// where the images overlap (region_choice.cc says how and why).
#pragma once

#include <optional>
#include <string>

#include "io/image_block.h"

namespace facets {

// The given region, else the block's, else the bulk of the well-covered tie points (2nd
// to 98th percentile per axis of the points inside the frames of at least half as many
// images as the best-covered points). `how`, when given, receives where the region came
// from, for the log. Throws std::runtime_error when there is none.
RegionOfInterest ChooseRegion(const ImageBlock& block, const std::optional<RegionOfInterest>& given,
                              std::string* how = nullptr);

// "x -40..40, y -35..35, z -3..20 m" (local coordinates, 6 significant digits).
std::string DescribeRegion(const RegionOfInterest& roi);

}  // namespace facets
