#include "io/input_file.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>

namespace facets {
namespace {

namespace fs = std::filesystem;

std::string ErrorOfOpening(const std::string& path) {
  try {
    OpenInputFile(path, "PLY file");
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}

TEST(InputFileTest, MissingFolderAndEmptyFilesAreNamed) {
  const fs::path dir = fs::path(testing::TempDir()) / "facets_input_file_test";
  fs::remove_all(dir);
  fs::create_directories(dir / "mesh.ply");
  std::ofstream(dir / "empty.ply").close();
  std::ofstream(dir / "one.ply") << "p";
  EXPECT_EQ(ErrorOfOpening((dir / "none.ply").string()), (dir / "none.ply").string() + ": PLY file not found");
  EXPECT_EQ(ErrorOfOpening((dir / "mesh.ply").string()),
            (dir / "mesh.ply").string() + ": is a folder, not a PLY file");
  EXPECT_EQ(ErrorOfOpening((dir / "empty.ply").string()),
            (dir / "empty.ply").string() + ": PLY file is empty (0 bytes)");
  EXPECT_EQ(ErrorOfOpening((dir / "one.ply").string()), "");
  EXPECT_NO_THROW(CheckInputFile((dir / "empty.ply").string(), "PLY file", /*allow_empty=*/true));
  fs::remove_all(dir);
}

TEST(InputFileTest, NearestKeyByEditDistance) {
  EXPECT_EQ(EditDistance("", ""), 0u);
  EXPECT_EQ(EditDistance("kitten", "sitting"), 3u);
  EXPECT_EQ(EditDistance("lamda", "lambda"), 1u);
  EXPECT_EQ(EditDistance("focal_lenght_mm", "focal_length_mm"), 2u);
  EXPECT_EQ(NearestName("omgea", {"omega", "phi", "kappa"}), "omega");
  EXPECT_EQ(NearestName("x", {}), "");
  EXPECT_EQ(UnknownKeyMessage("tie_point", {"images", "tie_points"}),
            "unknown key 'tie_point' (nearest known key: 'tie_points')");
}

}  // namespace
}  // namespace facets
