// Tests only: the real data sets (COLMAP models and photographs) kept beside the
// repository. One setting finds them: the environment variable FACETS_SHARED_DATA, else
// the folder compiled in by cmake/FacetsHelpers.cmake (../shared/data beside the source
// tree). A test that needs them skips, naming the missing folder, when they are absent,
// so the test command passes on a clone of the repository alone.
#pragma once

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <string>

namespace facets {

// The data folder with a trailing '/', e.g. "/work/shared/data/".
inline std::string SharedDataDir() {
  const char* env = std::getenv("FACETS_SHARED_DATA");
  std::string dir = env && *env ? std::string(env) : std::string(FACETS_SHARED_DATA_DIR);
  if (dir.back() != '/') dir += '/';
  return dir;
}

// Empty when SharedDataDir() + relative exists, else the reason to skip, naming it.
inline std::string MissingSharedData(const std::string& relative) {
  const std::string path = SharedDataDir() + relative;
  if (std::filesystem::exists(path)) return {};
  return "shared data " + path +
         " is missing (set FACETS_SHARED_DATA to the folder holding the real data sets)";
}

}  // namespace facets

// Skips the calling test when SharedDataDir() + relative does not exist.
#define FACETS_SKIP_WITHOUT_SHARED_DATA(relative)                                    \
  if (const std::string facets_missing = ::facets::MissingSharedData(relative);     \
      !facets_missing.empty())                                                       \
  GTEST_SKIP() << facets_missing
