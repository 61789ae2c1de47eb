// The memory estimate grows with the images' number and size, gives the kept level
// images to the byte, and an absurd job fails the check at once (the available memory
// is a parameter here, not read from the machine).
#include "engine/pipeline/memory_estimate.h"

#include <gtest/gtest.h>

#include <stdexcept>
#include <string>

namespace facets {
namespace {

MemoryJob Job(int images, int width, int height) {
  MemoryJob job;
  job.images.assign(images, ImageHeader{width, height, 3, 8});
  job.levels = 3;
  job.threads = 2;
  job.surface_m2 = 400.0;
  job.edge_m = 1.0;
  return job;
}

TEST(MemoryEstimate, GrowsWithTheImagesCountAndSize) {
  for (bool tiled : {false, true}) {
    MemoryJob few = Job(2, 1000, 800), many = Job(6, 1000, 800), large = Job(2, 2000, 1600);
    for (MemoryJob* job : {&few, &many, &large}) {
      job->tiled = tiled;
      job->tile_cache_mb = 64.0;
    }
    const MemoryEstimate a = EstimateMemory(few), b = EstimateMemory(many), c = EstimateMemory(large);
    EXPECT_GE(b.TotalMb(), a.TotalMb()) << tiled;
    EXPECT_GT(c.TotalMb(), a.TotalMb()) << tiled;
    EXPECT_GT(c.images_mb, a.images_mb) << tiled;
    if (!tiled) {
      EXPECT_GT(b.pyramid_mb, a.pyramid_mb);
    }
  }
  // Grey level images kept from level 0: 1000 x 800 + 500 x 400 + 250 x 200 floats each.
  const MemoryEstimate two = EstimateMemory(Job(2, 1000, 800));
  EXPECT_DOUBLE_EQ(two.pyramid_mb, 2.0 * (800000 + 200000 + 50000) * 4.0 / (1024.0 * 1024.0));
  MemoryJob coarser = Job(2, 1000, 800);
  coarser.finest_level = 1;
  EXPECT_DOUBLE_EQ(EstimateMemory(coarser).pyramid_mb, 2.0 * (200000 + 50000) * 4.0 / (1024.0 * 1024.0));
  // A larger surface or a finer TIN: more vertices, Embree and equations.
  MemoryJob wide = Job(2, 1000, 800);
  wide.surface_m2 = 4 * 400.0;
  // 2 / (sqrt(3) e^2) vertices per m^2: 461.9 on 400 m^2 at 1 m, 1847.5 on 1600 m^2.
  EXPECT_EQ(two.tin_vertices, 462);
  EXPECT_EQ(EstimateMemory(wide).tin_vertices, 1848);
  EXPECT_GT(EstimateMemory(wide).embree_mb, two.embree_mb);
  EXPECT_GT(EstimateMemory(wide).equations_mb, two.equations_mb);
}

TEST(MemoryEstimate, AnAbsurdJobFailsTheCheckNamingWhatToChange) {
  MemoryJob job = Job(500, 20000, 20000);
  job.threads = 8;
  job.surface_m2 = 1e8;
  job.edge_m = 0.1;
  const MemoryEstimate estimate = EstimateMemory(job);
  EXPECT_GT(estimate.TotalMb(), 1e6);
  try {
    CheckMemoryFits(estimate, job, MemoryLimit{4096.0, "test limit"});
    FAIL() << "an absurd job passed the check";
  } catch (const std::runtime_error& e) {
    const std::string message = e.what();
    for (const char* part : {"memory estimate: ", "images ", "pyramid ", "Embree ", "normal equations ",
                             "available 4.00 GB (test limit)", "does not fit", "--image-memory", "--roi",
                             "--finest-level 1", "--threads"}) {
      EXPECT_NE(message.find(part), std::string::npos) << part << "\n" << message;
    }
  }
  // The same job fits a machine large enough; a small job fits a small one.
  EXPECT_NO_THROW(CheckMemoryFits(estimate, job, MemoryLimit{2.0 * estimate.TotalMb(), "large"}));
  const MemoryJob small = Job(2, 1000, 800);
  EXPECT_NO_THROW(CheckMemoryFits(EstimateMemory(small), small, MemoryLimit{4096.0, "test limit"}));
}

}  // namespace
}  // namespace facets
