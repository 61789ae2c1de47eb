// Writing results so that a crash or an error never leaves a half-written file: write
// to "<path>.tmp", then rename over the final name.
#pragma once

#include <string>
#include <string_view>

namespace facets {

// Writes content to path via path + ".tmp" and a rename. Throws std::runtime_error
// naming the file when it cannot be written; the temporary is removed then.
void WriteFileAtomically(const std::string& path, std::string_view content);

// Renames a finished temporary file to its final name (for writers that produce the
// temporary themselves, e.g. OpenImageIO). Throws std::runtime_error naming the file.
void CommitTemporary(const std::string& tmp, const std::string& path);

}  // namespace facets
