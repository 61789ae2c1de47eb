// The fuzz input as a file, for readers that only take a path (the project reader, the
// --config file of the command line): an anonymous in-memory file (memfd), named by its
// /proc/self/fd path, so runs write nothing to disk and never collide.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

namespace facets {

class FuzzInputFile {
 public:
  FuzzInputFile(const uint8_t* data, size_t size);
  ~FuzzInputFile();
  FuzzInputFile(const FuzzInputFile&) = delete;
  FuzzInputFile& operator=(const FuzzInputFile&) = delete;

  const std::string& path() const { return path_; }

 private:
  int fd_ = -1;
  std::string path_;
};

}  // namespace facets
