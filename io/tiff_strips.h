// The compressed strips of a TIFF decoded with libtiff, to find damaged data that
// OpenImageIO reads without a word: OpenImageIO 2.4 inflates the strips of a deflate
// TIFF itself and drops zlib's error (a damaged strip comes back as wrong pixels).
#pragma once

#include <string>

namespace facets {

// Decodes every strip of the first image of the TIFF at `path` when its strips are
// deflate-compressed (other codecs, and tiles, are decoded by libtiff inside OpenImageIO,
// which reports their errors); nothing for other files. Throws std::runtime_error naming
// the file, the strip and libtiff's message when a strip does not decode. Memory: one
// strip.
void CheckDeflateTiffStrips(const std::string& path);

}  // namespace facets
