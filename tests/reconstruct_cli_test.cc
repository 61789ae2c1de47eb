// `facets reconstruct` through the built binary: the help shows the user's options in
// groups and the expert ones only with --help-all; bad values and unknown config keys
// are errors naming them; a scene preset sets its options and those given win; the
// settings.ini a run writes repeats it bit for bit through --config; a block whose region
// only one image sees stops with a non-zero exit.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <sstream>
#include <string>

#include "io/folder_snapshot_for_testing.h"
#include "io/colmap_io.h"

namespace facets {
namespace {
namespace fs = std::filesystem;

// Runs the facets CLI with `args`; returns the exit status, stdout in *out and stderr in
// *err (files per process: ctest -j runs tests side by side).
int Facets(const std::string& args, std::string* out = nullptr, std::string* err = nullptr) {
  const std::string stem = testing::TempDir() + "/facets_reconstruct_cli_" + std::to_string(getpid());
  const std::string command = std::string(FACETS_CLI) + " " + args + " > " + stem + ".out 2> " + stem + ".err";
  const int status = std::system(command.c_str());
  if (out != nullptr) *out = FileText(stem + ".out");
  if (err != nullptr) *err = FileText(stem + ".err");
  if (status != 0) std::cout << "facets " << args << ": status " << status << "\n" << FileText(stem + ".err");
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

// Option lines of a help text: lines whose first non-blank characters are "-".
int OptionLines(const std::string& help) {
  std::istringstream lines(help);
  int count = 0;
  for (std::string line; std::getline(lines, line);) {
    const size_t first = line.find_first_not_of(' ');
    if (first != std::string::npos && first > 0 && line[first] == '-') ++count;
  }
  return count;
}

TEST(ReconstructCli, HelpListsTheUserOptionsInGroupsAndHelpAllTheExpertOnes) {
  std::string help, all;
  ASSERT_EQ(Facets("reconstruct --help", &help), 0);
  ASSERT_EQ(Facets("reconstruct --help-all", &all), 0);
  std::cout << help;
  EXPECT_LE(OptionLines(help), 30) << help;
  for (const char* group : {"Input:", "Region:", "Quality:", "Products:", "Performance:"}) {
    EXPECT_NE(help.find(group), std::string::npos) << group;
  }
  for (const char* option : {"--colmap", "--images", "--project", "--out", "--scene", "--roi", "--levels",
                             "--radiometry", "--threads", "--image-memory", "--no-glb", "--config"}) {
    EXPECT_NE(help.find(option), std::string::npos) << option;
  }
  EXPECT_EQ(help.find("Expert:"), std::string::npos);
  EXPECT_EQ(help.find("--normal-search-rounds"), std::string::npos);
  EXPECT_NE(all.find("Expert:"), std::string::npos);
  for (const char* option : {"--normal-search-rounds", "--v-cycles", "--wall-corners", "--break-off-gsd",
                             "--silhouette-weight", "--no-fold-lips"}) {
    EXPECT_NE(all.find(option), std::string::npos) << option;
  }
  EXPECT_GT(OptionLines(all), 60);
  std::cout << "reconstruct --help: " << OptionLines(help) << " options, --help-all: " << OptionLines(all) << "\n";
}

TEST(ReconstructCli, BadValuesUnknownKeysAndDeletedFlagsAreErrorsNamingThem) {
  const fs::path dir = fs::path(testing::TempDir()) / "facets_reconstruct_cli_errors";
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::string err;
  EXPECT_NE(Facets("reconstruct --scene aerail --out " + (dir / "run").string(), nullptr, &err), 0);
  EXPECT_NE(err.find("aerail"), std::string::npos) << err;
  std::ofstream(dir / "bad.ini") << "[reconstruct]\nlevles=2\n";
  EXPECT_NE(Facets("reconstruct --config " + (dir / "bad.ini").string() + " --out " + (dir / "run").string(),
                   nullptr, &err),
            0);
  EXPECT_NE(err.find("levles"), std::string::npos) << err;
  EXPECT_NE(err.find("bad.ini"), std::string::npos) << err;
  for (const char* deleted : {"--thorough-walls", "--wall-passes 1", "--polish 2", "--straighten-by-kind",
                              "--plumb-walls 1", "--plumb-gate 15", "--plumb-no-corner-gate",
                              "--normal-search-corners", "--normal-search-support", "--normal-search-max-here 1",
                              "--sector-regularisation"}) {
    EXPECT_NE(Facets(std::string("reconstruct --out ") + (dir / "run").string() + " " + deleted, nullptr, &err), 0)
        << deleted;
  }
  EXPECT_FALSE(fs::exists(dir / "run" / "tin.ply"));
}

// The aerial preset sets one V-cycle and the wall crease steps; options given win over
// it; settings.ini repeats a run through --config, and the command line wins over it.
TEST(ReconstructCli, ScenePresetSetsItsOptionsAndGivenOptionsWin) {
  const fs::path dir = fs::path(testing::TempDir()) / "facets_reconstruct_cli_scene";
  fs::remove_all(dir);
  const std::string scene = std::string(FACETS_SOURCE_DIR) + "/scenes/data/seed_gable_parallel.json";
  ASSERT_EQ(Facets("render " + scene + " --out " + (dir / "scene").string()), 0);
  const std::string base = "reconstruct --colmap " + (dir / "scene" / "sparse").string() + " --images " +
                           (dir / "scene" / "images").string() +
                           " --levels 2 --max-iterations 2 --roi -6 -6 0 6 6 9 --no-glb --no-vrml --no-rasters "
                           "--no-preview --out ";
  auto log_of = [&](const std::string& name, const std::string& extra) {
    EXPECT_EQ(Facets(base + (dir / name).string() + extra), 0);
    return FileText(dir / name / "facets.log");
  };
  const std::string aerial = log_of("aerial", " --scene aerial --keep-levels");
  EXPECT_NE(aerial.find("scene: aerial (given)"), std::string::npos) << aerial;
  EXPECT_NE(aerial.find("memory estimate: "), std::string::npos) << aerial;
  for (const char* set : {"v-cycles=1", "facet-pixels=1.5", "wall-corners=true", "wall-feet=true", "wall-eaves=true"}) {
    EXPECT_NE(aerial.find(set), std::string::npos) << set << "\n" << aerial;
  }
  EXPECT_NE(aerial.find("options given: levels=2"), std::string::npos) << aerial;
  EXPECT_NE(aerial.find("geometry check: 2 of 2 images usable"), std::string::npos) << aerial;
  EXPECT_NE(FileText(dir / "aerial" / "report.json").find("\"geometry_check\""), std::string::npos);
  EXPECT_NE(aerial.find("stage v-cycle 1/1"), std::string::npos);
  EXPECT_EQ(aerial.find("stage v-cycle 1/2"), std::string::npos);
  const std::string ini = FileText(dir / "aerial" / "settings.ini");
  for (const char* key : {"scene=\"aerial\"", "wall-corners=true", "no-fold-lips=false", "v-cycles=1", "levels=2"}) {
    EXPECT_NE(ini.find(key), std::string::npos) << key << "\n" << ini;
  }
  for (const char* name : {"level_1.ply", "level_0.ply", "level_0_creases.ply"}) {
    EXPECT_GT(FileText(dir / "aerial" / "levels" / name).size(), 1000u) << name;
  }
  const std::string none = log_of("none", " --scene aerial --no-wall-corners --no-wall-feet --no-wall-eaves");
  EXPECT_EQ(none.find("corners:"), std::string::npos) << none;
  EXPECT_NE(FileText(dir / "none" / "settings.ini").find("\nwall-corners=false"), std::string::npos);
  const std::string two = log_of("two", " --scene aerial --v-cycles 2 --facet-pixels 2");
  EXPECT_NE(two.find("v-cycles=2"), std::string::npos) << two;
  EXPECT_NE(two.find("stage v-cycle 2/2"), std::string::npos);

  const fs::path again = dir / "again";
  ASSERT_EQ(Facets("reconstruct --config " + (dir / "two" / "settings.ini").string() + " --out " + again.string()), 0);
  const std::string tin = FileText(dir / "two" / "tin.ply");
  EXPECT_GT(tin.size(), 1000u);
  EXPECT_EQ(FileText(again / "tin.ply"), tin);
  ASSERT_EQ(Facets("reconstruct --config " + (dir / "two" / "settings.ini").string() + " --out " +
                   (dir / "one").string() + " --v-cycles 1"),
            0);
  const std::string one = FileText(dir / "one" / "facets.log");
  EXPECT_NE(one.find("stage v-cycle 1/1"), std::string::npos) << one;
  EXPECT_EQ(one.find("stage v-cycle 1/2"), std::string::npos) << one;
}

// A job whose estimate exceeds the address space allowed (ulimit -v) stops before any
// pixel is read, with the estimate, the limit and what to change, and writes no products.
TEST(ReconstructCli, AJobThatCannotFitStopsAtOnceWithTheEstimate) {
  const fs::path dir = fs::path(testing::TempDir()) / "facets_reconstruct_cli_memory";
  fs::remove_all(dir);
  const std::string scene = std::string(FACETS_SOURCE_DIR) + "/scenes/data/seed_gable_parallel.json";
  ASSERT_EQ(Facets("render " + scene + " --out " + (dir / "scene").string()), 0);
  // 1 km x 1 km at the gable's 0.24 m ground pixel: about half a million TIN vertices.
  const std::string command = "ulimit -v 3000000; " + std::string(FACETS_CLI) + " reconstruct --colmap " +
                              (dir / "scene" / "sparse").string() + " --images " + (dir / "scene" / "images").string() +
                              " --roi -500 -500 0 500 500 9 --out " + (dir / "run").string() + " > " +
                              (dir / "out.txt").string() + " 2> " + (dir / "err.txt").string();
  const int status = std::system(command.c_str());
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 1);
  const std::string err = FileText(dir / "err.txt"), out = FileText(dir / "out.txt");
  std::cout << err;
  for (const char* part : {"memory estimate: ", "normal equations ", "available ", "RLIMIT_AS", "does not fit",
                           "--roi", "--finest-level 1"}) {
    EXPECT_NE(err.find(part), std::string::npos) << part << "\n" << err;
  }
  EXPECT_EQ(out.find("stage images"), std::string::npos) << out;
  EXPECT_FALSE(fs::exists(dir / "run" / "tin.ply"));
}

// One image of the seed pair turned 180 degrees about its optical axis: it looks beside
// the region (the frames are cut to it), its tie points miss by thousands of pixels, the
// other image is left alone with the region, and the run stops before any work, naming both.
TEST(ReconstructCli, RunStopsWhenOnlyOneImageSeesTheRegion) {
  const fs::path dir = fs::path(testing::TempDir()) / "facets_reconstruct_cli_one_image";
  fs::remove_all(dir);
  const std::string scene = std::string(FACETS_SOURCE_DIR) + "/scenes/data/seed_gable_parallel.json";
  ASSERT_EQ(Facets("render " + scene + " --out " + (dir / "scene").string()), 0);
  ImageBlock block = ReadColmapModel((dir / "scene" / "sparse").string());
  BlockImage& turned = block.images[1];
  const Eigen::Vector3d centre = turned.ProjectionCentre();
  turned.cam_from_world.rotation = Eigen::Quaterniond(0, 0, 0, 1) * turned.cam_from_world.rotation;
  turned.cam_from_world.translation = -(turned.cam_from_world.rotation * centre);
  WriteColmapModel(block, (dir / "turned").string());
  std::string out, err;
  EXPECT_EQ(Facets("reconstruct --colmap " + (dir / "turned").string() + " --images " +
                       (dir / "scene" / "images").string() + " --levels 2 --out " + (dir / "run").string(),
                   &out, &err),
            1);
  EXPECT_NE(err.find("error: geometry check: 0 of 2 images usable"), std::string::npos) << err;
  EXPECT_NE(err.find("image 2 (img_01.png): it sees 0 of the region's"), std::string::npos) << err;
  EXPECT_NE(err.find("image 1 (img_00.png): no other usable image sees its region points"), std::string::npos)
      << err;
  EXPECT_NE(out.find("warning: image 2 (img_01.png) dropped: it sees 0"), std::string::npos) << out;
  EXPECT_FALSE(fs::exists(dir / "run" / "tin.ply"));
}

}  // namespace
}  // namespace facets
