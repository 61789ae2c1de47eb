#include "engine/pipeline/scene_preset.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <string>
#include <unistd.h>

#include "io/colmap_io.h"
#include "io/shared_data_for_testing.h"
#include "tests/rendered_scene.h"

namespace facets {
namespace {

namespace fs = std::filesystem;

TEST(ScenePreset, NamesRoundTripAndAnUnknownNameIsAnError) {
  for (const char* name : {"auto", "aerial", "facade", "object"}) {
    EXPECT_EQ(ScenePresetName(ParseScenePreset(name)), name);
  }
  EXPECT_THROW(ParseScenePreset("aerail"), std::invalid_argument);
}

TEST(ScenePreset, AerialSetsTheWallBundleOverTheDefaults) {
  ReconstructionOptions options;
  ApplyScenePreset(ScenePreset::kAerial, &options);
  EXPECT_EQ(options.levels, 4);
  EXPECT_EQ(options.facet_pixels, 1.5);
  EXPECT_EQ(options.v_cycles, 1);
  EXPECT_TRUE(options.wall_corners && options.wall_feet && options.wall_eaves);
  EXPECT_EQ(options.windows.partition.margin_rings, 1);
  ReconstructionOptions untouched;
  ApplyScenePreset(ScenePreset::kAuto, &untouched);
  EXPECT_EQ(untouched.levels, ReconstructionOptions().levels);
  EXPECT_FALSE(untouched.wall_corners);
  EXPECT_EQ(untouched.windows.partition.margin_rings, 2);
}

// The seed's nadir stereo pair: both images look straight down with the same heading, so
// their mean up is a horizontal direction; the choice must still be aerial.
TEST(ScenePreset, RenderedNadirPairIsAerial) {
  const RenderedScene rendered = RenderAndRead("scenes/data/seed_gable_parallel.json");
  std::string why;
  EXPECT_EQ(ChooseScenePreset(rendered.block, &why), ScenePreset::kAerial) << why;
  std::printf("seed pair: %s\n", why.c_str());
}

struct RealSet {
  const char* name;
  const char* sparse;
  ScenePreset expected;
};

// The kite-aerial village (nadir), the fountain from the street, the temple all around.
TEST(ScenePreset, RealSetsGetTheirKind) {
  const RealSet sets[] = {
      {"boruszyn_kap", "sparse_georef_local2180", ScenePreset::kAerial},
      {"strecha_fountain-P11", "sparse_with_points", ScenePreset::kFacade},
      {"middlebury_templeSparseRing", "sparse_with_points", ScenePreset::kObject},
  };
  for (const RealSet& set : sets) {
    FACETS_SKIP_WITHOUT_SHARED_DATA(std::string(set.name) + "/" + set.sparse);
    const std::string root = SharedDataDir() + set.name;
    const ImageBlock block = ReadColmapModel(root + "/" + set.sparse, root + "/images");
    std::string why;
    EXPECT_EQ(ChooseScenePreset(block, &why), set.expected) << set.name << ": " << why;
    std::printf("%s: %s\n", set.name, why.c_str());
  }
}

}  // namespace
}  // namespace facets
