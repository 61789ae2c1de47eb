// Project file reader (io/project_io, JSON). A std::runtime_error is the reader's
// message for bad input; anything else is a finding.
#include <cstddef>
#include <cstdint>
#include <stdexcept>

#include "fuzz/fuzz_input_file.h"
#include "io/project_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const facets::FuzzInputFile file(data, size);
  try {
    facets::ReadProject(file.path());
  } catch (const std::runtime_error&) {
  }
  return 0;
}
