// Tests only: a file's bytes, and a folder's files with their bytes, to compare output
// folders before and after a run.
#pragma once

#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <string>

namespace facets {

inline std::string FileText(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

// Every file below `dir` (relative name -> bytes; "->target" for a symbolic link, which
// is not followed); empty when `dir` does not exist.
inline std::map<std::string, std::string> FolderSnapshot(const std::filesystem::path& dir) {
  namespace fs = std::filesystem;
  std::map<std::string, std::string> files;
  if (!fs::exists(dir)) return files;
  for (const auto& entry : fs::recursive_directory_iterator(dir)) {
    const std::string name = entry.path().lexically_relative(dir).string();
    if (entry.is_symlink()) {
      files[name] = "->" + fs::read_symlink(entry.path()).string();
    } else if (entry.is_regular_file()) {
      files[name] = FileText(entry.path());
    }
  }
  return files;
}

}  // namespace facets
