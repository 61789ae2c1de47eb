// PLY reader (io/ply_read.cc): ascii and binary PLY files of any origin. A
// std::runtime_error is the reader's message for bad input; a mesh it returns must pass
// MeshData::Check (attribute sizes, face indices in range).
#include <cstddef>
#include <cstdint>
#include <sstream>
#include <stdexcept>
#include <string>

#include "io/ply_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::istringstream in{std::string(reinterpret_cast<const char*>(data), size)};
  facets::MeshData mesh;
  try {
    mesh = facets::ReadPly(in, "fuzz.ply");
  } catch (const std::runtime_error&) {
    return 0;
  }
  mesh.Check("fuzz.ply");  // throws std::invalid_argument: an uncaught exception is a finding
  return 0;
}
