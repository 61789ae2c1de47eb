// COLMAP text model reader (io/colmap_io): the input is cameras.txt, images.txt and
// points3D.txt separated by NUL bytes; without a second NUL there is no points3D.txt.
// A std::runtime_error (the reader's message for bad input) is the expected outcome;
// anything else (another exception, a sanitizer report, a crash) is a finding.
#include <cstddef>
#include <cstdint>
#include <sstream>
#include <stdexcept>
#include <string>
#include <string_view>

#include "io/colmap_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::string_view input(reinterpret_cast<const char*>(data), size);
  std::string_view parts[3];
  int count = 0;
  while (count < 2) {
    const size_t nul = input.find('\0');
    if (nul == std::string_view::npos) break;
    parts[count++] = input.substr(0, nul);
    input.remove_prefix(nul + 1);
  }
  parts[count++] = input;
  std::istringstream cameras{std::string(parts[0])};
  std::istringstream images{std::string(count > 1 ? parts[1] : std::string_view())};
  std::istringstream points{std::string(parts[2])};
  try {
    facets::ReadColmapModel(cameras, images, count > 2 ? &points : nullptr, "fuzz");
  } catch (const std::runtime_error&) {
  }
  return 0;
}
