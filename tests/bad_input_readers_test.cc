// Bad input to `facets reconstruct`, one reader at a time: the COLMAP text model, the
// images, the project file, the --config file and the region. Each case starts from a
// small valid block (two 64 x 48 images) with one thing broken, and must be refused
// before any reconstruction work (tests/bad_input.h says what every case asserts).
#include <OpenImageIO/imageio.h>

#include <cstdint>
#include <cstring>
#include <string>
#include <utility>
#include <vector>

#include "io/image_io.h"
#include "tests/bad_input.h"

namespace facets::bad_input {
namespace {

constexpr int kWidth = 64, kHeight = 48;

// A grey ramp with 3 bits of noise (a linear congruential sequence): deflate codes it
// with Huffman blocks (pure noise would be stored uncompressed, where damage cannot be
// told from data), and the strip is long enough to damage.
ImagePlanes NoiseImage() {
  ImagePlanes image;
  image.width = kWidth;
  image.height = kHeight;
  image.channels = 1;
  image.data.resize(kWidth * kHeight);
  uint32_t state = 12345;
  for (int y = 0; y < kHeight; ++y) {
    for (int x = 0; x < kWidth; ++x) {
      state = state * 1664525u + 1013904223u;
      image.data[y * kWidth + x] = static_cast<float>((x * 3 + y * 2 + (state >> 29)) % 256);
    }
  }
  return image;
}

// A valid block in `dir`: sparse/{cameras,images,points3D}.txt, images/a.png and b.png,
// and project.json describing the same block. The tie point's two observations make the
// radiometry choice read both images first thing.
void WriteValidBlock(const fs::path& dir) {
  WriteText(dir / "sparse" / "cameras.txt", "# CAMERA_ID MODEL WIDTH HEIGHT PARAMS[]\n1 PINHOLE 64 48 60 60 32 24\n");
  WriteText(dir / "sparse" / "images.txt",
            "# two lines per image\n1 1 0 0 0 0 0 10 1 a.png\n32 24 1\n2 1 0 0 0 -1 0 10 1 b.png\n26 24 1\n");
  WriteText(dir / "sparse" / "points3D.txt", "# POINT3D_ID X Y Z R G B ERROR TRACK[]\n1 0 0 0 9 9 9 0.5 1 0 2 0\n");
  fs::create_directories(dir / "images");
  WriteImage((dir / "images" / "a.png").string(), NoiseImage());
  WriteImage((dir / "images" / "b.png").string(), NoiseImage());
  WriteText(dir / "project.json", R"({
  "format": "facets-project", "version": 1,
  "cameras": [{"id": 1, "focal_length_mm": 0.06, "pixel_size_um": 1.0, "width_px": 64, "height_px": 48}],
  "images": [
    {"id": 1, "path": "images/a.png", "camera": 1, "projection_centre": [0, 0, 10], "omega": 0, "phi": 0, "kappa": 0},
    {"id": 2, "path": "images/b.png", "camera": 1, "projection_centre": [1, 0, 10], "omega": 0, "phi": 0, "kappa": 0}
  ],
  "tie_points": [{"id": 1, "xyz": [0, 0, 0], "track": [[1, 0], [2, 0]]}]
})");
}

// Replaces the first occurrence of `from` in the file by `to`.
void Edit(const fs::path& path, const std::string& from, const std::string& to) {
  std::string text = FileText(path);
  const size_t at = text.find(from);
  ASSERT_NE(at, std::string::npos) << from << " not in " << path;
  WriteText(path, text.replace(at, from.size(), to));
}

class BadBlock : public testing::Test {
 protected:
  void SetUp() override {
    dir_ = CaseFolder();
    WriteValidBlock(dir_);
  }
  std::string Colmap() const {
    return "reconstruct --colmap " + (dir_ / "sparse").string() + " --images " + (dir_ / "images").string() +
           " --out " + Out().string();
  }
  // The region around the one tie point, which both cameras see 10 m away with a 1 m base:
  // the geometry check passes and the run goes on to read the images.
  std::string ColmapInRegion() const { return Colmap() + " --roi -1 -1 -0.5 1 1 0.5"; }
  std::string Project() const {
    return "reconstruct --project " + (dir_ / "project.json").string() + " --out " + Out().string();
  }
  fs::path Out() const { return dir_ / "run"; }
  fs::path Sparse(const std::string& name) const { return dir_ / "sparse" / name; }

  // One file of the valid COLMAP model replaced by `text`, and the words its error must hold.
  struct ModelFile {
    std::string name, text;
    std::vector<std::string> needles;
  };
  void ExpectContentsRefused(const std::vector<ModelFile>& cases) {
    for (const ModelFile& c : cases) {
      WriteValidBlock(dir_);
      WriteText(Sparse(c.name), c.text);
      ExpectRefused(Colmap(), c.needles, Out());
    }
  }

  fs::path dir_;
};

TEST_F(BadBlock, ColmapCameras) {
  WriteText(Sparse("cameras.txt"), "");
  ExpectRefused(Colmap(), {"cameras.txt", "is empty"}, Out());
  WriteText(Sparse("cameras.txt"), "# only a comment\n\n");
  ExpectRefused(Colmap(), {"cameras.txt", "is empty: no camera lines"}, Out());
  fs::remove(Sparse("cameras.txt"));
  ExpectRefused(Colmap(), {"cameras.txt", "not found"}, Out());
  fs::create_directories(Sparse("cameras.txt"));
  ExpectRefused(Colmap(), {"cameras.txt", "is a folder"}, Out());
  fs::remove(Sparse("cameras.txt"));
  ExpectContentsRefused({
      {"cameras.txt", "1 PINHOLE_FISH 64 48 60 60 32 24\n", {"cameras.txt:1", "PINHOLE_FISH"}},
      {"cameras.txt", "1 PINHOLE 64 48 60 60 32\n", {"cameras.txt:1", "needs 4 parameters, got 3"}},
      {"cameras.txt", "1 PINHOLE 64 48 nan 60 32 24\n", {"cameras.txt:1", "camera parameter 0 is not finite"}},
  });
  fs::remove(Sparse("cameras.txt"));
  WriteText(dir_ / "sparse" / "cameras.bin", "binary");
  ExpectRefused(Colmap(), {"sparse", "binary COLMAP model"}, Out());
}

TEST_F(BadBlock, ColmapImagesAndPoints) {
  ExpectContentsRefused({
      {"images.txt", "", {"images.txt", "is empty"}},
      {"images.txt", "# nothing\n", {"images.txt", "is empty: no image lines"}},
      {"images.txt", "1 1 0 0 0 0 0 10 7 a.png\n\n", {"images.txt:1", "unknown CAMERA_ID 7"}},
      {"images.txt", "1 0 0 0 0 0 0 10 1 a.png\n\n", {"images.txt:1", "quaternion"}},
      {"images.txt", "1 1 0 0 0 0 0 10\n\n", {"images.txt:1", "truncated line"}},
      {"images.txt", "1 1 0 0 0 0 0 10 1 a.png\n3.5 4.5\n", {"images.txt:2", "not a multiple of 3"}},
      {"points3D.txt", "", {"points3D.txt", "is empty"}},
      {"points3D.txt", "1 0 0 0 9 9 9 0.5 1 0 5 0\n", {"points3D.txt:1", "unknown IMAGE_ID 5"}},
      {"points3D.txt", "1 0 zero 0 9 9 9 0.5 1 0 2 0\n", {"points3D.txt:1", "Y is not a number ('zero')"}},
  });
}

TEST_F(BadBlock, ColmapFolders) {
  ExpectRefused("reconstruct --colmap " + (dir_ / "nowhere").string() + " --images " + (dir_ / "images").string() +
                    " --out " + Out().string(),
                {"nowhere", "COLMAP model folder does not exist"}, Out());
  ExpectRefused("reconstruct --colmap " + (dir_ / "sparse").string() + " --images " + (dir_ / "imgs").string() +
                    " --out " + Out().string(),
                {"imgs", "image folder does not exist"}, Out());
  ExpectRefused("reconstruct --out " + Out().string(), {"give --project FILE, or --colmap"}, Out());
}

// A deflate TIFF written by OpenImageIO, then bytes in the middle of its first strip
// flipped: the file opens, its header is fine, its pixels cannot be decoded.
void WriteCorruptTiff(const fs::path& path) {
  const ImagePlanes image = NoiseImage();
  std::vector<uint8_t> pixels(image.data.begin(), image.data.end());
  auto out = OIIO::ImageOutput::create(path.string());
  ASSERT_TRUE(out);
  OIIO::ImageSpec spec(kWidth, kHeight, 1, OIIO::TypeDesc::UINT8);
  spec.attribute("compression", "zip");
  ASSERT_TRUE(out->open(path.string(), spec));
  ASSERT_TRUE(out->write_image(OIIO::TypeDesc::UINT8, pixels.data()));
  ASSERT_TRUE(out->close());
  // The first strip's offset and length from the first IFD (little-endian TIFF:
  // StripOffsets tag 273, StripByteCounts tag 279; SHORT or LONG values, inline when they
  // fit in 4 bytes, else at the offset the entry holds).
  std::string bytes = FileText(path);
  ASSERT_EQ(bytes.substr(0, 2), "II");
  auto u16 = [&](size_t at) { uint16_t v; std::memcpy(&v, bytes.data() + at, 2); return v; };
  auto u32 = [&](size_t at) { uint32_t v; std::memcpy(&v, bytes.data() + at, 4); return v; };
  auto first_value = [&](size_t entry) -> uint32_t {
    const bool is_short = u16(entry + 2) == 3;
    const size_t at = (is_short ? 2 : 4) * u32(entry + 4) <= 4 ? entry + 8 : u32(entry + 8);
    return is_short ? u16(at) : u32(at);
  };
  const uint32_t ifd = u32(4);
  uint32_t strip = 0, length = 0;
  for (int e = 0; e < u16(ifd); ++e) {
    const size_t entry = ifd + 2 + 12 * e;
    if (u16(entry) == 273) strip = first_value(entry);
    if (u16(entry) == 279) length = first_value(entry);
  }
  ASSERT_LE(strip + length, bytes.size());
  ASSERT_GT(length, 64u) << "strip too short to damage";
  for (uint32_t k = length / 4; k < length / 2; ++k) bytes[strip + k] ^= 0x5A;
  WriteText(path, bytes);
}

// OpenImageIO 2.4.7 inflates deflate strips itself and decodes a damaged one without an
// error; the strips are decoded with libtiff first (io/tiff_strips.h). A JPEG cut short
// is decoded by libjpeg with grey in place of the missing rows and only a warning.
TEST_F(BadBlock, CorruptPixels) {
  WriteCorruptTiff(dir_ / "images" / "a.tif");
  Edit(Sparse("images.txt"), "a.png", "a.tif");
  ExpectRefused(ColmapInRegion(), {"a.tif", "cannot decode the pixels of strip 1 of", "corrupt deflate data"}, Out());
  WriteImage((dir_ / "images" / "b.jpg").string(), NoiseImage());
  const std::string jpeg = FileText(dir_ / "images" / "b.jpg");
  WriteText(dir_ / "images" / "b.jpg", jpeg.substr(0, jpeg.size() * 2 / 3));
  WriteValidBlock(dir_);
  Edit(Sparse("images.txt"), "b.png", "b.jpg");
  ExpectRefused(ColmapInRegion(), {"b.jpg", "cannot decode the pixels", "Premature end of JPEG file"}, Out());
}

TEST_F(BadBlock, Images) {
  Edit(Sparse("images.txt"), "a.png", "a.tif");
  WriteText(dir_ / "images" / "a.tif", "");
  ExpectRefused(ColmapInRegion(), {"a.tif", "image file is empty"}, Out());
  WriteText(dir_ / "images" / "a.tif", "this is not a TIFF\n");
  ExpectRefused(ColmapInRegion(), {"a.tif", "cannot read image"}, Out());
  ImagePlanes small = NoiseImage();
  small.width = 32;
  small.data.resize(32 * kHeight);
  WriteImage((dir_ / "images" / "b.png").string(), small);
  Edit(Sparse("images.txt"), "a.tif", "a.png");
  ExpectRefused(ColmapInRegion(), {"b.png", "32x48 pixels but camera 1 expects 64x48"}, Out());
  fs::remove(dir_ / "images" / "b.png");
  ExpectRefused(ColmapInRegion(), {"b.png", "not found"}, Out());
  WriteValidBlock(dir_);
  const std::string png = FileText(dir_ / "images" / "a.png");
  WriteText(dir_ / "images" / "a.png", png.substr(0, png.size() / 2));
  ExpectRefused(ColmapInRegion(), {"a.png", "cannot decode the pixels"}, Out());
}

// The image files are checked (readable, of their camera's size) before the geometry: with
// image 2 moved 10 km away the geometry check stops the run, but a missing or wrong-sized
// file is what is reported.
TEST_F(BadBlock, ImageFilesBeforeGeometry) {
  Edit(Sparse("images.txt"), "2 1 0 0 0 -1 0 10 1 b.png", "2 1 0 0 0 -1 0 10000 1 b.png");
  ExpectRefused(ColmapInRegion(), {"geometry check: 0 of 2 images usable", "image 2 (b.png)"}, Out());
  fs::remove(dir_ / "images" / "b.png");
  ExpectRefused(ColmapInRegion(), {"b.png", "not found"}, Out());
  EXPECT_EQ(RunFacets(ColmapInRegion()).err.find("geometry check"), std::string::npos);
  ImagePlanes small = NoiseImage();
  small.height = 24;
  small.data.resize(kWidth * 24);
  WriteImage((dir_ / "images" / "b.png").string(), small);
  ExpectRefused(ColmapInRegion(), {"b.png", "64x24 pixels but camera 1 expects 64x48"}, Out());
  EXPECT_EQ(RunFacets(ColmapInRegion()).err.find("geometry check"), std::string::npos);
}

// One edit of the valid project file and the words its error must hold.
struct ProjectEdit {
  std::string from, to;
  std::vector<std::string> needles;
};

TEST_F(BadBlock, ProjectFile) {
  const fs::path project = dir_ / "project.json";
  const std::vector<ProjectEdit> edits = {
      {"\"focal_length_mm\"", "\"focal_lenght_mm\"",
       {"cameras[0]", "'focal_lenght_mm'", "nearest known key: 'focal_length_mm'"}},
      {"\"tie_points\"", "\"tie_point\"", {"top level", "'tie_point'", "'tie_points'"}},
      {"\"omega\"", "\"omgea\"", {"images[0]", "'omgea'", "'omega'"}},
      {"\"xyz\"", "\"xzy\"", {"tie_points[0]", "'xzy'", "'xyz'"}},
      {"\"images\": [", "\"region_of_interest\": {\"min\": [0, 0, 5], \"max\": [1, 1, 2]},\n \"images\": [",
       {"region_of_interest", "min Z > max Z"}},
      {"\"pixel_size_um\": 1.0", "\"pixel_size_um\": -1.0", {"cameras[0].pixel_size_um must be positive"}},
      {"\"camera\": 1, \"projection_centre\": [1", "\"camera\": 3, \"projection_centre\": [1",
       {"images[1].camera refers to unknown camera 3"}},
      {"{\"id\": 2,", "{\"id\": 1,", {"images[1].id duplicates image id 1"}},
      {"[2, 0]", "[9, 0]", {"tie_points[0].track[1][0] refers to unknown image 9"}},
      {"\"facets-project\"", "\"facets-projekt\"", {"format must be \"facets-project\""}},
      // Ids and indices are ints in the block: beyond INT_MAX they would wrap (4294967297 -> 1).
      {"{\"id\": 2,", "{\"id\": 4294967297,", {"images[1].id is 4294967297, outside 0..2147483647"}},
      {"[{\"id\": 1, \"focal", "[{\"id\": -1, \"focal", {"cameras[0].id is -1, outside 0..2147483647"}},
      {"[2, 0]", "[2, 2147483648]", {"tie_points[0].track[1][1] is 2147483648, outside 0..2147483647"}},
      {"\"width_px\": 64", "\"width_px\": 0", {"cameras[0].width_px is 0, outside 1..2147483647"}},
      {"{\"id\": 1, \"xyz\"", "{\"id\": 18446744073709551615, \"xyz\"",
       {"tie_points[0].id is 18446744073709551615, too large"}},
  };
  for (const ProjectEdit& edit : edits) {
    WriteValidBlock(dir_);
    Edit(project, edit.from, edit.to);
    std::vector<std::string> needles = edit.needles;
    needles.push_back("project.json");
    ExpectRefused(Project(), needles, Out());
  }
  WriteText(project, "{\"format\": \"facets-project\", \"version\": 1,");
  ExpectRefused(Project(), {"project.json", "not valid JSON"}, Out());
  WriteText(project, "");
  ExpectRefused(Project(), {"project.json", "project file is empty"}, Out());
  fs::remove(project);
  fs::create_directories(project);
  ExpectRefused(Project(), {"project.json", "is a folder"}, Out());
}

TEST_F(BadBlock, ConfigFileAndRegion) {
  const fs::path ini = dir_ / "bad.ini";
  WriteText(ini, "[reconstruct]\nlamda = 2\n");
  ExpectRefused(Colmap() + " --config " + ini.string(),
                {"bad.ini", "unknown key 'lamda' in [reconstruct]", "nearest known key: 'lambda' in [reconstruct]"},
                Out());
  WriteText(ini, "[reconstrukt]\nlevels = 2\n");
  ExpectRefused(Colmap() + " --config " + ini.string(),
                {"bad.ini", "unknown section [reconstrukt] (nearest known section: [reconstruct])"}, Out());
  WriteText(ini, "levels = 2\n");
  ExpectRefused(Colmap() + " --config " + ini.string(),
                {"bad.ini", "unknown key 'levels' outside any section (nearest known key: 'levels' in [reconstruct])"},
                Out());
  // A value its option refuses: the file and the key, not only CLI11's words.
  const std::vector<std::pair<std::string, std::vector<std::string>>> values = {
      {"levels = many", {"key 'levels' in [reconstruct]: bad value 'many'"}},
      {"levels = 99", {"key 'levels' in [reconstruct]: bad value '99'", "not in range 1 to 20"}},
      {"scene = moon", {"key 'scene' in [reconstruct]: bad value 'moon'"}},
      {"threads = -2", {"key 'threads' in [reconstruct]: bad value '-2'"}},
      {"no-glb = maybe", {"key 'no-glb' in [reconstruct]: bad value 'maybe'"}},
      {"normal-search = \" \"", {"key 'normal-search' in [reconstruct]: bad value ' '", "not a switch value"}},
      {"normal-search = 99999999999999999999", {"bad value '99999999999999999999'", "not a switch value"}},
  };
  for (const auto& [line, needles] : values) {
    WriteText(ini, "[reconstruct]\n" + line + "\n");
    std::vector<std::string> with_file = needles;
    with_file.push_back("config file " + ini.string() + ": ");
    ExpectRefused(Colmap() + " --config " + ini.string(), with_file, Out());
  }
  // The same bad value on the command line, with a good config file: not the file's fault.
  WriteText(ini, "[reconstruct]\nthreads = 1\n");
  const Outcome line_value = RunFacets(Colmap() + " --config " + ini.string() + " --levels many");
  EXPECT_GT(line_value.status, 0) << line_value.err;
  EXPECT_EQ(line_value.err.find("bad.ini"), std::string::npos) << line_value.err;
  EXPECT_NE(line_value.err.find("--levels"), std::string::npos) << line_value.err;
  // An empty output folder, given in the file or on the line: refused before anything is written.
  const std::string without_out = "reconstruct --colmap " + (dir_ / "sparse").string() + " --images " +
                                  (dir_ / "images").string();
  WriteText(ini, "[reconstruct]\nout = \"\"\n");
  ExpectRefused(without_out + " --config " + ini.string(), {"key 'out' in [reconstruct]", "output folder is empty"},
                Out());
  ExpectRefused(without_out + " --out ''", {"--out", "output folder is empty"}, Out());
  ExpectRefused(Colmap() + " --config " + (dir_ / "missing.ini").string(), {"missing.ini", "does not exist"}, Out());
  fs::create_directories(dir_ / "folder.ini");
  ExpectRefused(Colmap() + " --config " + (dir_ / "folder.ini").string(), {"folder.ini", "directory"}, Out());
  ExpectRefused(Colmap() + " --roi 0 0 50 10 10 10", {"--roi", "zmin 50 is not below zmax 10"}, Out());
  ExpectRefused(Colmap() + " --roi 5 0 0 5 10 10", {"--roi", "xmin 5 is not below xmax 5"}, Out());
  ExpectRefused(Colmap() + " --roi 0 0 0 1 1", {"--roi", "6 required but received 5"}, Out());
}

}  // namespace
}  // namespace facets::bad_input
