// Geometry checks of a block before any work (no pixel is read): a run must not end with
// a surface that one image alone determines, or that an image with a wrong orientation
// pulls off the truth.
//
// An image is usable when
//   - its pose and its camera hold usable numbers: finite, the projection centre and the
//     translation within kMaxCoordinate model units, the focal length within 0.01..10^4
//     times the image's larger side, the principal point within 10 focal lengths or image
//     sizes of the image, and a lens distortion that is one to one over the image and scales the
//     radius of the image corners by 1/3..3;
//   - its tie points, where it has 2D observations, reproject through the given camera
//     and pose with a median within GeometryCheckOptions::max_image_median_px (or, in a
//     block whose images all reproject worse, within max_image_median_ratio times the
//     typical image's median);
//   - it sees the region: at least min_region_points of the region's points project into
//     its frame in front of it (region points: a 7 x 7 x 3 grid of the region box and up
//     to 400 of the tie points inside it);
//   - another usable image sees at least min_region_points of those points with rays that
//     intersect at min_intersection_deg or more (stereo).
// Occlusion is not looked at: no surface is known yet.
#pragma once

#include <functional>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "io/image_block.h"

namespace facets {

// Coordinates (projection centres, translations) beyond this many model units are taken
// as corrupt: a million km in metres, beyond any block; local coordinates (the block's
// origin subtracted) keep real blocks far below.
inline constexpr double kMaxCoordinate = 1e9;

struct GeometryCheckOptions {
  // Degrees: rays from two images to a region point meeting at 2 deg have a base/height
  // ratio of 0.035, which makes depth about 29 times less precise than position across
  // the rays; narrower angles leave the surface height undetermined.
  double min_intersection_deg = 2.0;
  // Region points an image must see, and see with a stereo partner (a count).
  int min_region_points = 3;
  // Pixels of the original images: least-squares matching at the finest level pulls in
  // over 1-2 pixels; an image whose tie points miss by more than 5 px does not fit the
  // others there and would drag the surface.
  double max_image_median_px = 5.0;
  // A share of the typical image's median (the lower median over the images): a block
  // whose images all reproject worse than 5/3 px (large images, a weaker adjustment)
  // keeps its images and drops only those 3 times worse than the rest; well oriented
  // blocks' image medians lie within a factor of 2 of each other.
  double max_image_median_ratio = 3.0;
};

struct ImageGeometry {
  int image_id = 0;
  std::string name;
  int observations = 0;  // tie-point observations (2D points with a track)
  // Median reprojection error of its tie points (px); NaN without observations,
  // +inf when more than half of them lie behind the camera or do not project.
  double median_reprojection_px = std::numeric_limits<double>::quiet_NaN();
  int region_points_seen = 0;    // region points projecting into its frame
  int region_points_stereo = 0;  // of those, seen by another usable image at a usable angle
  std::vector<std::string> problems;  // why it is not usable; empty: usable
  bool Usable() const { return problems.empty(); }
};

struct GeometryCheck {
  std::vector<ImageGeometry> images;  // in block order
  int region_points = 0;
  double min_intersection_deg = 0.0;
  long long observations = 0;
  // Over all observations of all images (px); NaN without observations.
  double median_reprojection_px = std::numeric_limits<double>::quiet_NaN();
  // The lower median of the images' medians, and the bound above which an image is
  // dropped: max(max_image_median_px, max_image_median_ratio * typical) (px).
  double typical_image_median_px = std::numeric_limits<double>::quiet_NaN();
  double bad_image_median_px = std::numeric_limits<double>::quiet_NaN();
  // Whether the relative bound applied (the block's images all reproject poorly).
  bool relative_bound = false;
  int worst_image = -1;  // index into images of the largest median; -1 without observations

  int UsableCount() const;
  // "geometry check: ..." (counts, reprojection) and one "warning: ..." per image dropped.
  std::vector<std::string> Lines() const;
};

// Throws std::runtime_error when two images name the same image file (the resolved
// path where known, else the name): the message names the file and both images.
void CheckImageFilesUnique(const ImageBlock& block);

// The checks above over every image of the block, for the region. Throws like
// CheckImageFilesUnique; never for an unusable image (see KeepUsableImages).
GeometryCheck CheckBlockGeometry(const ImageBlock& block, const RegionOfInterest& region,
                                 const GeometryCheckOptions& options = {});

// The block without the images `check` found unusable: their track elements and the
// cameras no kept image uses removed. Throws std::runtime_error naming every image and
// why it is unusable when fewer than 2 usable images remain.
ImageBlock KeepUsableImages(const ImageBlock& block, const GeometryCheck& check);

// A block as a reconstruction works on it: the images the checks found unusable removed,
// and the geometry check's result.
struct CheckedImageBlock {
  ImageBlock block;
  GeometryCheck geometry;
};

// What every reconstruction runs on the block it is given before any pixel is read:
// the image files' headers first (CheckImageHeaders: each file readable, its size its
// camera's), so that a file problem is reported as such; then the region (ChooseRegion
// with `given`), CheckBlockGeometry, its lines said, KeepUsableImages.
CheckedImageBlock CheckBlock(const ImageBlock& block, const std::optional<RegionOfInterest>& given,
                             const std::function<void(const std::string&)>& say);

}  // namespace facets
