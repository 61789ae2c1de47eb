// The native Facets project file (JSON, photogrammetric terms: omega-phi-kappa, focal
// length in mm, pixel size in micrometres, projection centres in global object
// coordinates). The format is specified in docs/PROJECT_FILE.md.
#pragma once

#include <istream>
#include <string>

#include "io/image_block.h"

namespace facets {

ImageBlock ReadProject(const std::string& path);   // image paths resolved relative to the file
void WriteProject(const ImageBlock& block, const std::string& path);

}  // namespace facets
