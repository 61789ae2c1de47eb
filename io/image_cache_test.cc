#include "io/image_cache.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <stdexcept>
#include <vector>

namespace facets {
namespace {

TEST(TiledImages, RegionsReadBackExactly) {
  ImagePlanes image;
  image.width = 203;  // not a multiple of the 64-pixel tiles
  image.height = 130;
  image.channels = 3;
  image.data.resize(static_cast<size_t>(image.width) * image.height * image.channels);
  for (int c = 0; c < 3; ++c)
    for (int y = 0; y < image.height; ++y)
      for (int x = 0; x < image.width; ++x) image.at(c, x, y) = 1000.0f * c + x + 0.001f * y;
  const std::string path = testing::TempDir() + "/facets_tiled_test.tif";
  WriteTiledFloatImage(path, image);
  ASSERT_FALSE(std::filesystem::exists(path + ".tmp"));
  const TiledImageReader reader(16.0);
  // A region across tile borders, one clipped at the image's corner, the whole image.
  for (const auto& r : {std::array<int, 4>{50, 60, 140, 129}, std::array<int, 4>{190, 120, 260, 400},
                        std::array<int, 4>{0, 0, 203, 130}}) {
    const ImagePlanes region = reader.Read(path, r[0], r[1], r[2], r[3]);
    EXPECT_EQ(region.x0, r[0]);
    EXPECT_EQ(region.y0, r[1]);
    EXPECT_EQ(region.width, std::min(r[2], 203) - r[0]);
    EXPECT_EQ(region.height, std::min(r[3], 130) - r[1]);
    EXPECT_EQ(region.channels, 3);
    int wrong = 0;
    for (int c = 0; c < 3; ++c)
      for (int y = region.y0; y < region.y0 + region.height; ++y)
        for (int x = region.x0; x < region.x0 + region.width; ++x)
          wrong += region.at(c, x, y) != image.at(c, x, y);
    EXPECT_EQ(wrong, 0);
    EXPECT_TRUE(region.Holds(r[0], r[1]));
    EXPECT_FALSE(region.Holds(r[0] - 1, r[1]));
  }
  EXPECT_GT(reader.MemoryMb(), 0.0);
  EXPECT_THROW(reader.Read(testing::TempDir() + "/facets_no_such.tif", 0, 0, 4, 4), std::runtime_error);
}

// A writer given fewer rows than the image has refuses to close and, destroyed, leaves
// neither the file nor its temporary.
TEST(TiledImages, AnUnfinishedFileIsRemoved) {
  const std::string path = testing::TempDir() + "/facets_tiled_unfinished.tif";
  std::filesystem::remove(path);
  {
    TiledFloatImageWriter writer(path, 100, 70, 2);
    const std::vector<float> row(200, 1.0f);
    for (int y = 0; y < 69; ++y) writer.AddRow(row.data());
    EXPECT_THROW(writer.Close(), std::logic_error);
  }
  EXPECT_FALSE(std::filesystem::exists(path));
  EXPECT_FALSE(std::filesystem::exists(path + ".tmp"));
}

}  // namespace
}  // namespace facets
