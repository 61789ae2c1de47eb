// What the readers share when they refuse input: an input file opened with a message
// that says what is wrong with it (missing, a folder, empty), and the known key nearest
// to a misspelt one.
#pragma once

#include <cstdint>
#include <fstream>
#include <string>
#include <string_view>
#include <vector>

namespace facets {

// Opens `path` for reading in binary mode. Throws std::runtime_error naming the file when
// it does not exist, is a folder, cannot be opened, or (unless `allow_empty`) has 0 bytes;
// `what` names the expected kind in the message ("PLY file", "project file").
std::ifstream OpenInputFile(const std::string& path, const std::string& what,
                            bool allow_empty = false);

// Checks the same as OpenInputFile without opening (for readers that open by name).
void CheckInputFile(const std::string& path, const std::string& what, bool allow_empty = false);

// Levenshtein distance: insertions, deletions and substitutions of one byte each.
size_t EditDistance(std::string_view a, std::string_view b);

// The candidate nearest to `key` by EditDistance (the first of equally near ones);
// "" without candidates.
std::string NearestName(std::string_view key, const std::vector<std::string>& candidates);

// "unknown key 'focal_lenght_mm' (nearest known key: 'focal_length_mm')".
std::string UnknownKeyMessage(std::string_view key, const std::vector<std::string>& known);

}  // namespace facets
