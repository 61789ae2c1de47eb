// Writing results so that a crash or an error never leaves a half-written file, and so
// that nothing planted beside the file is followed: the content goes to a new file with
// a unique name in the same folder, created exclusively (O_CREAT | O_EXCL | O_NOFOLLOW:
// an existing file or symbolic link of that name is never opened), and is then renamed
// over the final name (a rename replaces a symbolic link there, it never writes through
// it). The temporary names are ".<name>.facets-XXXXXX" (hidden, never "*.tmp").
#pragma once

#include <string>
#include <string_view>

namespace facets {

// Writes content to path through a unique temporary file and a rename. Throws
// std::runtime_error naming the file when it cannot be written; the temporary is
// removed then.
void WriteFileAtomically(const std::string& path, std::string_view content);

// Creates an empty file with a unique name beside path (exclusively, as above) and
// returns its name, for writers that open the file by name themselves (OpenImageIO,
// GDAL). Finish with CommitTemporary, or RemoveTemporary when the writer failed. Throws
// std::runtime_error naming path when the folder is not writable.
std::string CreateTemporaryBeside(const std::string& path);

// Renames a finished temporary file to its final name. Throws std::runtime_error naming
// the file (the temporary is removed then).
void CommitTemporary(const std::string& tmp, const std::string& path);

// Removes a temporary file, ignoring errors (cleanup on a failure path).
void RemoveTemporary(const std::string& tmp);

// A name of `length` characters from [a-z0-9], different on every call (for unique
// file and folder names; uniqueness is checked by the exclusive create, not here).
std::string RandomNameSuffix(int length);

}  // namespace facets
