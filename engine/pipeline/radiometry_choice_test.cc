#include "engine/pipeline/radiometry_choice.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <unistd.h>

#include "io/colmap_io.h"
#include "io/image_io.h"
#include "io/shared_data_for_testing.h"
#include "tests/rendered_scene.h"

namespace facets {
namespace {

namespace fs = std::filesystem;

std::string TempDir(const std::string& name) {
  return (fs::temp_directory_path() / ("facets_radiometry_" + name + "_" + std::to_string(getpid()))).string();
}

TEST(RadiometryChoice, NoObservationsGiveNone) {
  ImageBlock block;
  block.images.push_back({});
  block.points.push_back({});
  const RadiometryChoice choice = ChooseRadiometry(block);
  EXPECT_EQ(choice.model, RadiometricModel::kNone);
  EXPECT_EQ(choice.why, "no tie-point observations");
}

// A rendered pair has one exposure: no radiometric model. One image's grey values
// scaled by 1.3 and written back make the gains differ: linear.
TEST(RadiometryChoice, RenderedPairNoneAndScaledImageLinear) {
  RenderedScene rendered = RenderAndRead("scenes/data/seed_gable_parallel.json");
  const RadiometryChoice consistent = ChooseRadiometry(rendered.block);
  std::printf("rendered pair: %s\n", consistent.why.c_str());
  EXPECT_EQ(consistent.model, RadiometricModel::kNone) << consistent.why;
  EXPECT_EQ(consistent.images_fitted, 2);

  // The cached render is shared: the scaled image goes into a private copy.
  const std::string dir = CopyRender(rendered.dir, TempDir("gable"));
  rendered.block = ReadColmapModel(dir + "/sparse", dir + "/images");
  const std::string path = rendered.block.images[1].path;
  ImagePlanes image = ReadImage(path);
  for (float& g : image.data) g *= 1.3f;
  WriteImage(path, image, image.bits);
  const RadiometryChoice scaled = ChooseRadiometry(rendered.block);
  std::printf("one image x 1.3: %s\n", scaled.why.c_str());
  EXPECT_EQ(scaled.model, RadiometricModel::kLinear) << scaled.why;
  EXPECT_GT(scaled.gain_spread, 0.1);
  fs::remove_all(dir);
}

struct RealSet {
  const char* name;
  const char* sparse;
  RadiometricModel expected;
};

// The photographs of the shared data sets, where present: their exposure differs between
// shots (brightness at the mean grey value spreads 27 % over the kite images, 8 % over the
// fountain, 5 % over the temple; one exposure rendered: 0.5 % pair, 1.8 % oblique block).
TEST(RadiometryChoice, RealPhotographs) {
  const RealSet sets[] = {
      {"boruszyn_kap", "sparse_georef_local2180", RadiometricModel::kLinear},
      {"strecha_fountain-P11", "sparse_with_points", RadiometricModel::kLinear},
      {"middlebury_templeSparseRing", "sparse_with_points", RadiometricModel::kLinear},
  };
  for (const RealSet& set : sets) {
    FACETS_SKIP_WITHOUT_SHARED_DATA(std::string(set.name) + "/" + set.sparse);
    const std::string root = SharedDataDir() + set.name;
    const ImageBlock block = ReadColmapModel(root + "/" + set.sparse, root + "/images");
    const RadiometryChoice choice = ChooseRadiometry(block);
    std::printf("%s: %s\n", set.name, choice.why.c_str());
    EXPECT_EQ(choice.model, set.expected) << set.name << ": " << choice.why;
  }
}

}  // namespace
}  // namespace facets
