// Issue 6 acceptance, object lifting (seed 001): from a start 12 m off the truth, trial
// heights over a 30 m interval on the coarsest level find a start height within 1 m of
// the true mean height. Plus the choice rule on its own.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>

#include "tests/pyramid_gable.h"

namespace facets {
namespace {

TEST(Lifting, FindsTheMeanHeightWithinOneMetreFromThirtyMetres) {
  const PyramidGable gable;
  for (double offset : {12.0, -12.0}) {
    ReconstructionOptions options = PyramidGableOptions(3, gable.true_mean_height + offset);
    options.lifting_steps = 31;  // 1 m apart
    options.lifting_range = 30.0;
    const Reconstruction r = Reconstruct(gable.block, options);
    const double chosen = r.report.start_height;
    std::cout << "start " << offset << " m off: lifted to " << chosen << " m (true mean "
              << gable.true_mean_height << " m); " << r.report.BriefReport() << ", rms "
              << gable.Heights(r).rms << " m\n";
    ASSERT_EQ(r.report.lifting.size(), 31u);
    EXPECT_LT(std::abs(chosen - gable.true_mean_height), 1.0);  // measured: 0.01 m
  }
}

LiftingTrial Trial(double height, double sigma0, double mean_dn) {
  LiftingTrial t;
  t.height = height;
  t.sigma0 = sigma0;
  t.mean_dn = mean_dn;
  t.observations = 1000;
  return t;
}

TEST(Lifting, ChoiceBySignChangeNextToTheSmallestSigma0) {
  // A false sign change far off (large sigma0) and the true one between 4 and 6 m.
  const std::vector<LiftingTrial> trials = {
      Trial(-2, 20, 0.5), Trial(0, 21, -0.4), Trial(2, 15, 2.0), Trial(4, 9, 1.0),
      Trial(6, 9.5, -1.0), Trial(8, 14, -2.0)};
  EXPECT_NEAR(ChooseLiftedHeight(trials), 5.0, 1e-12);
  // No sign change: the smallest sigma0 plus its displacement.
  const std::vector<LiftingTrial> rising = {Trial(0, 12, 3.0), Trial(2, 8, 1.5), Trial(4, 10, 0.5)};
  EXPECT_NEAR(ChooseLiftedHeight(rising), 3.5, 1e-12);
  LiftingTrial unseen = Trial(0, 1e300, 0.0);
  unseen.observations = 0;
  EXPECT_THROW(ChooseLiftedHeight({unseen}), std::runtime_error);
}

}  // namespace
}  // namespace facets
