#include "io/image_io.h"

#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <stdexcept>

#include "io/shared_data_for_testing.h"

namespace facets {
namespace {

namespace fs = std::filesystem;

class ImageIoTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("facets_io_test_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string Path(const std::string& name) const { return (dir_ / name).string(); }

  fs::path dir_;
};

// A value that differs per channel and pixel and uses the full range of the type.
double Pattern(int c, int x, int y, double max_value) {
  if (c == 0 && x == 1 && y == 0) return max_value;
  const long long v = (37LL * x + 101LL * y + 4099LL * c + 13LL * x * y) % 997;
  return std::floor(v / 996.0 * max_value);
}

// Writes an interleaved test image with OpenImageIO directly (independent of
// WriteImage), returns the expected planes.
template <typename T>
ImagePlanes WriteWithOiio(const std::string& path, int width, int height, int channels,
                          OIIO::TypeDesc type, double max_value) {
  ImagePlanes expected;
  expected.width = width;
  expected.height = height;
  expected.channels = channels;
  expected.data.resize(static_cast<size_t>(width) * height * channels);
  std::vector<T> interleaved(expected.data.size());
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      for (int c = 0; c < channels; ++c) {
        const double v = Pattern(c, x, y, max_value);
        interleaved[(static_cast<size_t>(y) * width + x) * channels + c] = static_cast<T>(v);
        expected.at(c, x, y) = static_cast<float>(static_cast<T>(v));
      }
    }
  }
  auto out = OIIO::ImageOutput::create(path);
  EXPECT_TRUE(out) << path;
  OIIO::ImageSpec spec(width, height, channels, type);
  EXPECT_TRUE(out->open(path, spec)) << out->geterror();
  EXPECT_TRUE(out->write_image(type, interleaved.data())) << out->geterror();
  out->close();
  return expected;
}

void ExpectSamePixels(const ImagePlanes& expected, const ImagePlanes& actual) {
  ASSERT_EQ(actual.width, expected.width);
  ASSERT_EQ(actual.height, expected.height);
  ASSERT_EQ(actual.channels, expected.channels);
  ASSERT_EQ(actual.data.size(), expected.data.size());
  size_t mismatches = 0;
  float max_value = 0;
  for (size_t i = 0; i < expected.data.size(); ++i) {
    if (actual.data[i] != expected.data[i]) ++mismatches;
    max_value = std::max(max_value, actual.data[i]);
  }
  std::cout << "  " << actual.width << "x" << actual.height << "x" << actual.channels << ", "
            << actual.bits << " bit, max value " << max_value << ", " << mismatches
            << " mismatching samples of " << expected.data.size() << "\n";
  EXPECT_EQ(mismatches, 0u);
}

TEST_F(ImageIoTest, PlaneMajorLayout) {
  ImagePlanes image;
  image.width = 3;
  image.height = 2;
  image.channels = 2;
  image.data.resize(12);
  for (size_t i = 0; i < 12; ++i) image.data[i] = static_cast<float>(i);
  EXPECT_EQ(image.at(0, 0, 0), 0.0f);
  EXPECT_EQ(image.at(0, 2, 0), 2.0f);
  EXPECT_EQ(image.at(0, 0, 1), 3.0f);
  EXPECT_EQ(image.at(1, 0, 0), 6.0f);
  EXPECT_EQ(image.at(1, 2, 1), 11.0f);
  const ImagePlanes grey = image.Grey();
  EXPECT_EQ(grey.channels, 1);
  EXPECT_EQ(grey.at(0, 2, 1), (5.0f + 11.0f) / 2);
}

TEST_F(ImageIoTest, Reads8BitGreyPng) {
  const auto expected =
      WriteWithOiio<uint8_t>(Path("g8.png"), 37, 23, 1, OIIO::TypeDesc::UINT8, 255);
  const ImagePlanes image = ReadImage(Path("g8.png"));
  EXPECT_EQ(image.bits, 8);
  ExpectSamePixels(expected, image);
  EXPECT_EQ(*std::max_element(image.data.begin(), image.data.end()), 255.0f);
}

TEST_F(ImageIoTest, Reads16BitGreyPngAndTiff) {
  for (const char* name : {"g16.png", "g16.tif"}) {
    const auto expected =
        WriteWithOiio<uint16_t>(Path(name), 41, 19, 1, OIIO::TypeDesc::UINT16, 65535);
    const ImagePlanes image = ReadImage(Path(name));
    EXPECT_EQ(image.bits, 16) << name;
    ExpectSamePixels(expected, image);
    EXPECT_EQ(*std::max_element(image.data.begin(), image.data.end()), 65535.0f);
  }
}

TEST_F(ImageIoTest, ReadsRgbAndMultiChannel) {
  {
    const auto expected =
        WriteWithOiio<uint8_t>(Path("rgb.png"), 30, 20, 3, OIIO::TypeDesc::UINT8, 255);
    const ImagePlanes image = ReadImage(Path("rgb.png"));
    ExpectSamePixels(expected, image);
    const ImagePlanes grey = image.Grey();
    EXPECT_FLOAT_EQ(grey.at(0, 7, 11),
                    (image.at(0, 7, 11) + image.at(1, 7, 11) + image.at(2, 7, 11)) / 3);
  }
  for (int channels : {4, 5}) {
    const std::string name = "ms" + std::to_string(channels) + ".tif";
    const auto expected = WriteWithOiio<uint16_t>(Path(name), 25, 17, channels,
                                                  OIIO::TypeDesc::UINT16, 4095);
    const ImagePlanes image = ReadImage(Path(name));
    EXPECT_EQ(image.bits, 16);
    ExpectSamePixels(expected, image);
  }
  {
    const auto expected =
        WriteWithOiio<uint8_t>(Path("ms5_8.tif"), 16, 12, 5, OIIO::TypeDesc::UINT8, 255);
    ExpectSamePixels(expected, ReadImage(Path("ms5_8.tif")));
  }
  {
    const auto expected =
        WriteWithOiio<float>(Path("f32.tif"), 16, 12, 2, OIIO::TypeDesc::FLOAT, 1234.5);
    const ImagePlanes image = ReadImage(Path("f32.tif"));
    EXPECT_EQ(image.bits, 32);
    ExpectSamePixels(expected, image);
  }
}

// The header gives size, channels and depth; strips with an overlap give every row of
// the image exactly, each strip starting `overlap` rows before the previous one ends.
TEST_F(ImageIoTest, HeaderAndStripsMatchTheWholeImage) {
  const auto expected = WriteWithOiio<uint16_t>(Path("strips.png"), 23, 130, 3, OIIO::TypeDesc::UINT16, 65535);
  const ImageHeader header = ReadImageHeader(Path("strips.png"));
  EXPECT_EQ(header.width, 23);
  EXPECT_EQ(header.height, 130);
  EXPECT_EQ(header.channels, 3);
  EXPECT_EQ(header.bits, 16);
  std::vector<int> starts, heights;
  int wrong = 0;
  ForEachImageStrip(Path("strips.png"), 50, 4, [&](const ImagePlanes& strip) {
    starts.push_back(strip.y0);
    heights.push_back(strip.height);
    EXPECT_EQ(strip.bits, 16);
    for (int c = 0; c < 3; ++c)
      for (int y = strip.y0; y < strip.y0 + strip.height; ++y)
        for (int x = 0; x < strip.width; ++x) wrong += strip.at(c, x, y) != expected.at(c, x, y);
  });
  EXPECT_EQ(starts, (std::vector<int>{0, 46, 92}));
  EXPECT_EQ(heights, (std::vector<int>{50, 50, 38}));
  EXPECT_EQ(wrong, 0);
  EXPECT_THROW(ForEachImageStrip(Path("strips.png"), 4, 4, [](const ImagePlanes&) {}), std::invalid_argument);
  EXPECT_THROW(ReadImageHeader(Path("missing.png")), std::runtime_error);
}

TEST_F(ImageIoTest, WriteImageRoundTrip) {
  ImagePlanes image;
  image.width = 33;
  image.height = 21;
  image.channels = 3;
  image.data.resize(33 * 21 * 3);
  for (int c = 0; c < 3; ++c)
    for (int y = 0; y < 21; ++y)
      for (int x = 0; x < 33; ++x) image.at(c, x, y) = static_cast<float>(Pattern(c, x, y, 255));
  for (const char* name : {"w8.png", "w8.tif"}) {
    WriteImage(Path(name), image, 8);
    EXPECT_FALSE(fs::exists(Path(name) + ".tmp"));
    ExpectSamePixels(image, ReadImage(Path(name)));
  }
  // 16 bit: values beyond 255 survive.
  ImagePlanes wide = image;
  for (float& v : wide.data) v *= 200;
  WriteImage(Path("w16.png"), wide, 16);
  ExpectSamePixels(wide, ReadImage(Path("w16.png")));
  // 32-bit float keeps fractions and negative values exactly.
  ImagePlanes fractional = image;
  for (float& v : fractional.data) v = v * 0.37f - 20.125f;
  WriteImage(Path("w32.tif"), fractional, 32);
  const ImagePlanes read32 = ReadImage(Path("w32.tif"));
  EXPECT_EQ(read32.bits, 32);
  ExpectSamePixels(fractional, read32);
  // Rounding and clamping for integer files.
  ImagePlanes odd;
  odd.width = 4;
  odd.height = 1;
  odd.channels = 1;
  odd.data = {-3.0f, 12.4f, 12.6f, 300.0f};
  WriteImage(Path("clamp.png"), odd, 8);
  const ImagePlanes clamped = ReadImage(Path("clamp.png"));
  EXPECT_EQ(clamped.data, (std::vector<float>{0, 12, 13, 255}));
  // Formats that cannot hold the depth are refused rather than silently truncated.
  EXPECT_THROW(WriteImage(Path("bad.png"), fractional, 32), std::invalid_argument);
  EXPECT_THROW(WriteImage(Path("bad.jpg"), wide, 16), std::invalid_argument);
  EXPECT_THROW(WriteImage(Path("bad.png"), image, 12), std::invalid_argument);
}

TEST_F(ImageIoTest, ErrorsNameTheFile) {
  try {
    ReadImage(Path("missing.png"));
    FAIL();
  } catch (const std::runtime_error& e) {
    std::cout << "  error: " << e.what() << "\n";
    EXPECT_NE(std::string(e.what()).find(Path("missing.png")), std::string::npos);
  }
  {
    std::ofstream garbage(Path("x.png"), std::ios::binary);
    garbage << "this is not a PNG file at all \x01\x02\x03";
  }
  try {
    ReadImage(Path("x.png"));
    FAIL();
  } catch (const std::runtime_error& e) {
    std::cout << "  error: " << e.what() << "\n";
    EXPECT_NE(std::string(e.what()).find(Path("x.png")), std::string::npos);
  }
  WriteWithOiio<uint8_t>(Path("small.png"), 64, 48, 1, OIIO::TypeDesc::UINT8, 255);
  Camera camera = Camera::Create(CameraModel::kPinhole, 100, 100, 32, 24, 64, 48);
  camera.camera_id = 5;
  EXPECT_EQ(ReadImageFor(Path("small.png"), camera).width, 64);
  camera.height = 49;
  try {
    ReadImageFor(Path("small.png"), camera);
    FAIL();
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    std::cout << "  error: " << what << "\n";
    EXPECT_NE(what.find(Path("small.png")), std::string::npos);
    EXPECT_NE(what.find("64x48"), std::string::npos);
    EXPECT_NE(what.find("64x49"), std::string::npos);
  }
}

// A grey ramp with 3 bits of noise (a linear congruential sequence), written by
// OpenImageIO with `compression` and, when `tile` > 0, in tiles of tile x tile pixels:
// compressible enough to be coded (pure noise is stored), long enough to damage.
ImagePlanes WriteNoisy(const std::string& path, int width, int height, const std::string& compression, int tile) {
  ImagePlanes image;
  image.width = width;
  image.height = height;
  image.channels = 1;
  image.data.resize(static_cast<size_t>(width) * height);
  std::vector<uint8_t> pixels(image.data.size());
  uint32_t state = 12345;
  for (size_t i = 0; i < pixels.size(); ++i) {
    state = state * 1664525u + 1013904223u;
    pixels[i] = static_cast<uint8_t>((i % width * 3 + i / width * 2 + (state >> 29)) % 256);
    image.data[i] = pixels[i];
  }
  auto out = OIIO::ImageOutput::create(path);
  EXPECT_TRUE(out) << path;
  OIIO::ImageSpec spec(width, height, 1, OIIO::TypeDesc::UINT8);
  if (!compression.empty()) spec.attribute("compression", compression);
  if (tile > 0) spec.tile_width = spec.tile_height = tile;
  EXPECT_TRUE(out->open(path, spec)) << out->geterror();
  EXPECT_TRUE(out->write_image(OIIO::TypeDesc::UINT8, pixels.data())) << out->geterror();
  out->close();
  return image;
}

// Tiled TIFFs (OpenImageIO 2.4.7's read_scanlines divides by zero on them) read whole
// and in strips that do not line up with the tiles, the last tile row and column partial.
TEST_F(ImageIoTest, ReadsTiledTiffs) {
  const ImagePlanes expected = WriteNoisy(Path("tiled.tif"), 53, 45, "zip", 16);
  ASSERT_EQ(OIIO::ImageInput::open(Path("tiled.tif"))->spec().tile_width, 16);
  ExpectSamePixels(expected, ReadImage(Path("tiled.tif")));
  int wrong = 0, rows = 0;
  ForEachImageStrip(Path("tiled.tif"), 10, 3, [&](const ImagePlanes& strip) {
    for (int y = strip.y0; y < strip.y0 + strip.height; ++y, ++rows)
      for (int x = 0; x < strip.width; ++x) wrong += strip.at(0, x, y) != expected.at(0, x, y);
  });
  EXPECT_EQ(rows, 45 + 3 * 5);  // 6 strips starting 7 rows apart, 5 overlaps of 3 rows
  EXPECT_EQ(wrong, 0);
}

// Damaged image data is an error naming the file, for every compressed format: bytes
// flipped in the middle of the file (the coded pixels; the header stays whole) and the
// file cut in half. OpenImageIO returns true for most of them (libjpeg fills with grey,
// libtiff's LZW and OpenImageIO's own inflate of deflate strips with zeros).
TEST_F(ImageIoTest, DamagedPixelsAreErrors) {
  struct Case {
    const char* name;
    const char* compression;
    int tile;
  };
  const Case cases[] = {{"zip.tif", "zip", 0},  {"lzw.tif", "lzw", 0}, {"tiles.tif", "zip", 64},
                        {"plain.png", "", 0},    {"plain.jpg", "", 0}};
  for (const Case& c : cases) {
    for (const bool cut : {false, true}) {
      const std::string path = Path(std::string(cut ? "cut_" : "flipped_") + c.name);
      WriteNoisy(path, 256, 256, c.compression, c.tile);
      std::string bytes;
      {
        std::ifstream in(path, std::ios::binary);
        bytes.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
      }
      if (cut) {
        bytes.resize(bytes.size() / 2);
      } else {
        for (size_t k = bytes.size() * 2 / 5; k < bytes.size() / 2; ++k) bytes[k] ^= 0x5A;
      }
      std::ofstream(path, std::ios::binary | std::ios::trunc) << bytes;
      try {
        ReadImage(path);
        ADD_FAILURE() << path << " read without an error";
      } catch (const std::runtime_error& e) {
        const std::string what = e.what();
        std::cout << "  " << what.substr(0, 240) << "\n";
        EXPECT_NE(what.find(path + ": cannot decode the pixels"), std::string::npos) << what;
      }
      int strips = 0;
      EXPECT_THROW(ForEachImageStrip(path, 64, 0, [&](const ImagePlanes&) { ++strips; }), std::runtime_error) << path;
    }
  }
}

// The real images load in their raw layout and match their cameras.
TEST_F(ImageIoTest, ReadsRealImages) {
  const std::string data = SharedDataDir();
  struct Case {
    const char* file;
    int width, height;
  };
  const Case cases[] = {{"boruszyn_kap/images/img_4977.jpg", 1152, 864},
                        {"middlebury_templeSparseRing/images/templeSR0001.png", 640, 480}};
  for (const Case& c : cases) FACETS_SKIP_WITHOUT_SHARED_DATA(c.file);
  for (const Case& c : cases) {
    const ImagePlanes image = ReadImage(data + c.file);
    const ImagePlanes grey = image.Grey();
    double mean = 0;
    for (float v : grey.data) mean += v;
    mean /= grey.data.size();
    std::cout << "  " << c.file << ": " << image.width << "x" << image.height << "x"
              << image.channels << ", " << image.bits << " bit, mean grey " << mean << "\n";
    EXPECT_EQ(image.width, c.width);
    EXPECT_EQ(image.height, c.height);
    EXPECT_EQ(image.bits, 8);
    EXPECT_GT(mean, 5.0);
    EXPECT_LT(mean, 250.0);
  }
}

}  // namespace
}  // namespace facets
