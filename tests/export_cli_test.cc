// `facets export` (issue 8) through the real CLI: a small seed gable-roof run made by
// `facets render` + `facets reconstruct` (one pyramid level, a 12 m x 12 m ROI, two
// iterations: any reconstructed surface will do), re-exported into another folder.
// Every product must be re-created: PLY and glb with the vertex counts of the
// originals, the .wrl text identical (same coordinates, indices and atlas layout), the
// DSM identical (same geometry, same grid), the orthophoto within one grey value
// (surface.ply stores the grey values as 8 bit), the preview with its size. Bad run
// folders give a clear error and exit status 1.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>
#include <tiny_gltf.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <string>

#include "io/image_io.h"
#include "io/products_dir_for_testing.h"
#include "io/ply_io.h"
#include "io/preview.h"
#include "io/raster_io.h"

namespace facets {
namespace {
namespace fs = std::filesystem;

// Runs the facets CLI with `args`; returns the exit status, stderr in *err. The stderr
// file is per process: ctest -j runs this file's tests side by side, and with one shared
// file a test read another's (empty) stderr (CI, session 18).
int Facets(const std::string& args, std::string* err = nullptr) {
  const std::string err_file =
      testing::TempDir() + "/facets_export_cli_stderr_" + std::to_string(getpid()) + ".txt";
  const std::string command = std::string(FACETS_CLI) + " " + args + " > /dev/null 2> " + err_file;
  const int status = std::system(command.c_str());
  std::ifstream in(err_file);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (err != nullptr) *err = text;
  if (status != 0) std::cout << "facets " << args << ": status " << status << "\n" << text;
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

std::string FileText(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

// Vertices of all primitives of a .glb.
size_t GlbVertexCount(const fs::path& path) {
  tinygltf::TinyGLTF loader;
  tinygltf::Model model;
  std::string err, warn;
  EXPECT_TRUE(loader.LoadBinaryFromFile(&model, &err, &warn, path.string())) << path << ": " << err;
  size_t n = 0;
  for (const tinygltf::Mesh& mesh : model.meshes) {
    for (const tinygltf::Primitive& p : mesh.primitives) n += model.accessors.at(p.attributes.at("POSITION")).count;
  }
  return n;
}

TEST(ExportCli, ReExportsAReconstructedRun) {
  const fs::path dir = fs::path(testing::TempDir()) / "facets_export_cli";
  fs::remove_all(dir);
  const std::string scene = std::string(FACETS_SOURCE_DIR) + "/scenes/data/seed_gable_parallel.json";
  const fs::path run = dir / "run", exported = dir / "exported";
  ASSERT_EQ(Facets("render " + scene + " --out " + (dir / "scene").string()), 0);
  ASSERT_EQ(Facets("reconstruct --colmap " + (dir / "scene" / "sparse").string() + " --images " +
                   (dir / "scene" / "images").string() + " --out " + run.string() +
                   " --levels 1 --max-iterations 2 --roi -6 -6 0 6 6 9"),
            0);
  ASSERT_EQ(Facets("export " + run.string() + " --out " + exported.string()), 0);

  for (const char* name : {"surface.ply", "surface.glb", "surface.wrl", "surface_atlas.png",
                           "ortho.tif", "dsm.tif", "sigma.tif", "preview.png"}) {
    EXPECT_TRUE(fs::exists(run / name)) << "reconstruct did not write " << name;
    EXPECT_TRUE(fs::exists(exported / name)) << "export did not write " << name;
  }
  const MeshData original = ReadPly((run / "surface.ply").string());
  const MeshData again = ReadPly((exported / "surface.ply").string());
  EXPECT_EQ(again.vertices.size(), original.vertices.size());
  EXPECT_EQ(again.vertices, original.vertices);
  EXPECT_EQ(again.colors, original.colors);
  const size_t glb_original = GlbVertexCount(run / "surface.glb");
  const size_t glb_again = GlbVertexCount(exported / "surface.glb");
  EXPECT_EQ(glb_again, glb_original);
  EXPECT_EQ(glb_original, 3 * original.faces.size());  // textured: one vertex per corner
  EXPECT_EQ(FileText(exported / "surface.wrl"), FileText(run / "surface.wrl"));
  const Raster dsm = ReadGeoTiff((run / "dsm.tif").string(), original.origin);
  const Raster dsm_again = ReadGeoTiff((exported / "dsm.tif").string(), original.origin);
  EXPECT_EQ(dsm_again.data, dsm.data);
  const Raster ortho = ReadGeoTiff((run / "ortho.tif").string(), original.origin);
  const Raster ortho_again = ReadGeoTiff((exported / "ortho.tif").string(), original.origin);
  ASSERT_EQ(ortho_again.data.size(), ortho.data.size());
  float max_grey = 0;
  for (size_t i = 0; i < ortho.data.size(); ++i) {
    max_grey = std::max(max_grey, std::abs(ortho_again.data[i] - ortho.data[i]));
  }
  EXPECT_LE(max_grey, 1.0f);
  const ImagePlanes preview = ReadImage((exported / "preview.png").string());
  EXPECT_EQ(preview.width, 1200);
  EXPECT_EQ(preview.height, 500);
  // Both panels show the surface: background (PreviewOptions::background) well below
  // the whole panel (a square roof seen diagonally leaves about 2/3 of it).
  const PreviewOptions preview_options;
  for (int panel = 0; panel < 2; ++panel) {
    long long background = 0;
    for (int y = 0; y < preview.height; ++y) {
      for (int x = panel * 600; x < (panel + 1) * 600; ++x) {
        bool is_background = true;
        for (int c = 0; c < 3; ++c) {
          is_background = is_background && preview.at(c, x, y) == preview_options.background[c];
        }
        background += is_background;
      }
    }
    const double share = background / (600.0 * preview.height);
    std::cout << "preview panel " << panel << ": background share " << share << "\n";
    EXPECT_LT(share, 0.75);
  }
  std::cout << "export: " << again.vertices.size() << " PLY vertices, " << glb_again
            << " glb vertices, DSM " << dsm.grid.width << " x " << dsm.grid.height
            << " identical, orthophoto max difference " << max_grey << " grey values\n";

  // Only some formats, another raster pixel, a CRS given on the command line.
  const fs::path some = dir / "some";
  ASSERT_EQ(Facets("export " + run.string() + " --out " + some.string() +
                   " --formats dsm,glb --raster-pixel 0.5 --crs EPSG:25832"),
            0);
  EXPECT_TRUE(fs::exists(some / "dsm.tif"));
  EXPECT_TRUE(fs::exists(some / "surface.glb"));
  EXPECT_FALSE(fs::exists(some / "ortho.tif"));
  EXPECT_FALSE(fs::exists(some / "surface.ply"));
  std::string crs;
  const Raster coarse = ReadGeoTiff((some / "dsm.tif").string(), original.origin, &crs);
  EXPECT_DOUBLE_EQ(coarse.grid.pixel_size, 0.5);
  EXPECT_NE(crs.find("25832"), std::string::npos);

  // For scripts/validate-products.sh (FACETS_PRODUCTS_DIR): the run's glb / wrl as
  // reconstruct wrote them and as export re-writes them.
  const fs::path products = ProductsDir();
  fs::remove_all(products / "reconstructed_run");
  fs::create_directories(products / "reconstructed_run");
  for (const char* name : {"surface.glb", "surface.wrl", "surface_atlas.png"}) {
    fs::copy_file(run / name, products / "reconstructed_run" / name);
  }
  ASSERT_EQ(Facets("export " + run.string() + " --out " + (products / "exported_run").string() +
                   " --formats glb,wrl"),
            0);

  // Bad run folders and options: exit status 1 and a message naming the problem.
  std::string err;
  EXPECT_EQ(Facets("export " + (dir / "nothing").string() + " --out " + some.string(), &err), 1);
  EXPECT_NE(err.find("no such run folder"), std::string::npos) << err;
  EXPECT_EQ(Facets("export " + (dir / "scene").string() + " --out " + some.string(), &err), 1);
  EXPECT_NE(err.find("surface.ply: missing"), std::string::npos) << err;
  const fs::path incomplete = dir / "incomplete";
  fs::create_directories(incomplete);
  fs::copy_file(run / "surface.ply", incomplete / "surface.ply");
  EXPECT_EQ(Facets("export " + incomplete.string() + " --out " + some.string(), &err), 1);
  EXPECT_NE(err.find("report.json: missing"), std::string::npos) << err;
  EXPECT_EQ(Facets("export " + incomplete.string() + " --out " + some.string() +
                   " --formats glb,tiff", &err), 1);
  EXPECT_NE(err.find("unknown product format 'tiff'"), std::string::npos) << err;
  // Without rasters report.json is not needed.
  EXPECT_EQ(Facets("export " + incomplete.string() + " --out " + some.string() + " --formats wrl,preview"), 0);
}

// `facets creases` (session 34): the crease step without images on a real corner of
// block_oblique (tests/data/corner_patch.ply, walls x = 0 and y = 0, 0.72 m edges): one
// vertical corner found and laid, no crossing or fold added, the TIN written; bad input
// named.
TEST(CreasesCli, LaysTheRealCornerWithoutImagesAndNamesBadInput) {
  const fs::path dir = fs::path(testing::TempDir()) / "facets_creases_cli";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string patch = std::string(FACETS_SOURCE_DIR) + "/tests/data/corner_patch.ply";
  const fs::path out = dir / "laid.ply";
  const std::string command = std::string(FACETS_CLI) + " creases " + patch + " --edge 0.72 --no-feet --no-eaves --out " +
                              out.string() + " > " + (dir / "log.txt").string() + " 2>&1";
  ASSERT_EQ(std::system(command.c_str()), 0) << FileText(dir / "log.txt");
  const std::string log = FileText(dir / "log.txt");
  EXPECT_NE(log.find(" 1 vertical corners, 0 feet, 0 eaves"), std::string::npos) << log;
  EXPECT_NE(log.find("corner at ("), std::string::npos) << log;
  EXPECT_NE(log.find("summary: 1 creases found, 1 laid, 0 left"), std::string::npos) << log;
  EXPECT_GT(FileText(out).size(), 1000u);
  EXPECT_FALSE(fs::exists(out.string() + ".tmp"));

  std::string err;
  EXPECT_EQ(Facets("creases " + (dir / "missing.ply").string() + " --edge 0.72 --out " + (dir / "x.ply").string(), &err),
            1);
  EXPECT_NE(err.find("missing.ply"), std::string::npos) << err;
  EXPECT_EQ(Facets("creases " + patch + " --edge 0 --out " + (dir / "x.ply").string(), &err), 1);
  EXPECT_NE(err.find("--edge must be > 0"), std::string::npos) << err;
  EXPECT_FALSE(fs::exists(dir / "x.ply"));
}

}  // namespace
}  // namespace facets
