#include "io/image_subset.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>

namespace facets {
namespace {

// Images named in reverse order of their ids and positions (img_11 first, img_00 last),
// so a selection by name differs from one by position; tie point 7 seen by images 11,
// 10 and 9, tie point 8 by 11 and 10.
ImageBlock TwelveImages() {
  ImageBlock block;
  for (int i = 0; i < 12; ++i) {
    BlockImage image;
    image.image_id = 100 + i;
    image.name = "img_" + std::string(11 - i < 10 ? "0" : "") + std::to_string(11 - i) + ".jpg";
    block.images.push_back(image);
  }
  TiePoint seen_thrice;
  seen_thrice.point3d_id = 7;
  seen_thrice.track = {{100, 0}, {101, 0}, {102, 0}};
  TiePoint seen_twice;
  seen_twice.point3d_id = 8;
  seen_twice.track = {{100, 1}, {101, 1}};
  block.points = {seen_thrice, seen_twice};
  return block;
}

TEST(ImageSubsetTest, EveryFifthIsTheFifthTenthByName) {
  const ImageBlock block = TwelveImages();
  // By name: img_00 .. img_11 sit at block indices 11 .. 0; the 5th and 10th names are
  // img_04 (index 7) and img_09 (index 2).
  EXPECT_EQ(SelectImages(block, "every-5th"), (std::vector<int>{2, 7}));
  EXPECT_EQ(SelectImages(block, "every-5"), (std::vector<int>{2, 7}));
  EXPECT_EQ(SelectImages(block, "every-2nd"), (std::vector<int>{0, 2, 4, 6, 8, 10}));
  EXPECT_EQ(SelectImages(block, "every-13th"), (std::vector<int>{}));
  EXPECT_EQ(ImageNames(block, {2, 7}), "img_09.jpg, img_04.jpg");
}

TEST(ImageSubsetTest, ListsByNameOrFile) {
  const ImageBlock block = TwelveImages();
  EXPECT_EQ(SelectImages(block, "img_00.jpg, img_11.jpg,img_00.jpg"), (std::vector<int>{0, 11}));
  const char* tmp = std::getenv("TEST_TMPDIR");
  const std::string path = std::string(tmp ? tmp : "/tmp") + "/image_subset_list.txt";
  std::ofstream(path) << "# held out\nimg_03.jpg\n\n  img_05.jpg \n";
  EXPECT_EQ(SelectImages(block, path), (std::vector<int>{6, 8}));
  std::filesystem::remove(path);
}

TEST(ImageSubsetTest, RefusesUnknownNamesAndEveryFirst) {
  const ImageBlock block = TwelveImages();
  try {
    SelectImages(block, "img_00.jpg,nope.jpg");
    FAIL() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()),
              "image selection 'img_00.jpg,nope.jpg': no image named nope.jpg in the model");
  }
  EXPECT_THROW(SelectImages(block, "every-1st"), std::invalid_argument);
  EXPECT_THROW(SelectImages(block, " , "), std::invalid_argument);
}

TEST(ImageSubsetTest, WithoutImagesDropsTheirObservations) {
  const ImageBlock block = TwelveImages();
  const ImageBlock kept = WithoutImages(block, {0, 5});
  ASSERT_EQ(kept.images.size(), 10u);
  EXPECT_EQ(kept.images[0].image_id, 101);
  EXPECT_EQ(kept.images[4].image_id, 106);
  // Point 7 keeps images 101 and 102; point 8 keeps only 101 and is dropped.
  ASSERT_EQ(kept.points.size(), 1u);
  EXPECT_EQ(kept.points[0].point3d_id, 7);
  EXPECT_EQ(kept.points[0].track.size(), 2u);
}

}  // namespace
}  // namespace facets
