// Tests only: the folder where tests write export products for
// scripts/validate-products.sh (FACETS_PRODUCTS_DIR, else a folder in the test temp dir).
#pragma once

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>

namespace facets {

inline std::filesystem::path ProductsDir() {
  const char* env = std::getenv("FACETS_PRODUCTS_DIR");
  std::filesystem::path dir = env && *env ? std::filesystem::path(env)
                                          : std::filesystem::path(testing::TempDir()) / "facets_products";
  std::filesystem::create_directories(dir);
  return dir;
}

}  // namespace facets
