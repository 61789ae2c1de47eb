#include "engine/pipeline/background_choice.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <stdexcept>
#include <string>
#include <unistd.h>

#include "io/colmap_io.h"
#include "io/image_io.h"
#include "io/shared_data_for_testing.h"

namespace facets {
namespace {

namespace fs = std::filesystem;

constexpr int kWidth = 200, kHeight = 100;  // border band: 5 pixels (5 % of 100)

// A grey image: the object (grey 200) inside the band, the backdrop (grey 10) in it,
// and a bright patch of 5 x 10 pixels (grey 60) in the left band: 50 of the band's
// 2 900 pixels (1.7 %).
ImagePlanes ObjectBeforeBackdrop() {
  ImagePlanes image;
  image.width = kWidth;
  image.height = kHeight;
  image.channels = 1;
  image.data.assign(static_cast<size_t>(kWidth) * kHeight, 200.0f);
  for (int y = 0; y < kHeight; ++y) {
    for (int x = 0; x < kWidth; ++x) {
      const bool band = x < 5 || y < 5 || x >= kWidth - 5 || y >= kHeight - 5;
      if (band) image.at(0, x, y) = (x < 5 && y >= 40 && y < 50) ? 60.0f : 10.0f;
    }
  }
  return image;
}

ImageBlock BlockOfTwo(const std::string& dir) {
  fs::create_directories(dir);
  ImageBlock block;
  block.cameras[1] = Camera::Create(CameraModel::kPinhole, 300, 300, 100, 50, kWidth, kHeight);
  block.cameras[1].camera_id = 1;
  for (int id = 1; id <= 2; ++id) {
    BlockImage image;
    image.image_id = id;
    image.camera_id = 1;
    image.name = "view" + std::to_string(id) + ".png";
    image.path = dir + "/" + image.name;
    WriteImage(image.path, ObjectBeforeBackdrop());
    block.images.push_back(image);
  }
  return block;
}

// The hull's threshold (98th percentile of the band) stays on the backdrop, the
// silhouette term's (99.5th) reaches the bright patch; the object inside counts nowhere.
TEST(BackgroundChoice, BorderQuantilesOfABackdropWithABrightPatch) {
  const std::string dir = (fs::temp_directory_path() / ("facets_background_" + std::to_string(getpid()))).string();
  const ImageBlock block = BlockOfTwo(dir);
  const BackgroundChoice choice = ChooseBackground(block);
  EXPECT_EQ(choice.border_pixels, 2 * 2900);
  EXPECT_NEAR(choice.hull_background, 10.0, 0.07);
  EXPECT_NEAR(choice.silhouette_background, 60.0, 0.07);
  EXPECT_NE(choice.why.find("5800 pixels"), std::string::npos) << choice.why;
  fs::remove_all(dir);
}

TEST(BackgroundChoice, AnImageOfTheWrongSizeIsNamed) {
  const std::string dir = (fs::temp_directory_path() / ("facets_background_size_" + std::to_string(getpid()))).string();
  ImageBlock block = BlockOfTwo(dir);
  block.cameras[1] = Camera::Create(CameraModel::kPinhole, 300, 300, 100, 50, kWidth + 1, kHeight);
  try {
    ChooseBackground(block);
    ADD_FAILURE() << "no error for images of the wrong size";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("view1.png"), std::string::npos) << e.what();
  }
  fs::remove_all(dir);
}

TEST(BackgroundChoice, NoImageFileIsAnError) {
  ImageBlock block;
  block.cameras[1] = Camera::Create(CameraModel::kPinhole, 300, 300, 100, 50, kWidth, kHeight);
  BlockImage image;
  image.camera_id = 1;
  block.images.push_back(image);
  EXPECT_THROW(ChooseBackground(block), std::invalid_argument);
}

// The temple's black backdrop with a grey cloth at the sides: the border puts the
// background's top near the grey values a hand search found best (hull 30, outline 40).
TEST(BackgroundChoice, TempleBackdropAndCloth) {
  FACETS_SKIP_WITHOUT_SHARED_DATA("middlebury_templeSparseRing/sparse");
  const std::string root = SharedDataDir() + "middlebury_templeSparseRing";
  const BackgroundChoice choice = ChooseBackground(ReadColmapModel(root + "/sparse", root + "/images"));
  EXPECT_EQ(choice.border_pixels, 16LL * 51456);
  EXPECT_NEAR(choice.hull_background, 31.3, 0.1) << choice.why;
  EXPECT_NEAR(choice.silhouette_background, 38.7, 0.1) << choice.why;
}

}  // namespace
}  // namespace facets
