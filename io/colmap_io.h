// COLMAP text model (cameras.txt, images.txt, points3D.txt) <-> ImageBlock.
//
// images.txt stores cam_from_world (QW QX QY QZ TX TY TZ), which is exactly
// BlockImage::cam_from_world. The 2D keypoint line of each image is parsed and
// checked but not stored (Facets only needs the 3D tie points and their tracks).
// Parsing uses std::locale::classic(); errors throw std::runtime_error naming the
// file, the line number and what is wrong.
#pragma once

#include <istream>
#include <string>

#include "io/image_block.h"

namespace facets {

// Reads cameras.txt, images.txt and (optional) points3D.txt from sparse_dir.
// image_dir, when not empty, resolves BlockImage::path = image_dir / name and checks the
// file exists (error names the missing file). origin stays zero.
ImageBlock ReadColmapModel(const std::string& sparse_dir, const std::string& image_dir = "");
// istream overloads for tests (points may be nullptr).
ImageBlock ReadColmapModel(std::istream& cameras, std::istream& images, std::istream* points,
                           const std::string& source_name = "<stream>");
// Writes cameras.txt, images.txt, points3D.txt (creating sparse_dir), full precision
// (%.17g), each file via temp name + rename. Coordinates are written as stored (local).
void WriteColmapModel(const ImageBlock& block, const std::string& sparse_dir);

}  // namespace facets
