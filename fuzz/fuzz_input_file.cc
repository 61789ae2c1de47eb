#include "fuzz/fuzz_input_file.h"

#include <sys/mman.h>
#include <unistd.h>

#include <cstdlib>
#include <cstdio>

namespace facets {

FuzzInputFile::FuzzInputFile(const uint8_t* data, size_t size) {
  fd_ = memfd_create("facets_fuzz_input", MFD_CLOEXEC);
  if (fd_ < 0) {
    std::perror("memfd_create");
    std::abort();
  }
  for (size_t written = 0; written < size;) {
    const ssize_t n = write(fd_, data + written, size - written);
    if (n <= 0) {
      std::perror("write to memfd");
      std::abort();
    }
    written += static_cast<size_t>(n);
  }
  path_ = "/proc/self/fd/" + std::to_string(fd_);
}

FuzzInputFile::~FuzzInputFile() { close(fd_); }

}  // namespace facets
