#include "backend/ba/disparity_offset_calibration.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

namespace dala {
namespace {

// Estimates of a rig with a real offset (KITTI-like: ~0.3 px, windows agreeing to ~0.05 px):
// the offset is used from the min_estimates-th estimate on, follows the running mean, and the
// calibration stops once that mean is stable.
TEST(DisparityOffsetCalibration, AppliesAnAgreedOffsetAndConverges) {
  DisparityOffsetCalibration c;
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0.3, 0.05);
  for (int i = 0; i < 7; ++i) {
    c.Add(noise(rng));
    EXPECT_EQ(c.offset_px(), 0.0) << "estimate " << i + 1 << ": before min_estimates";
  }
  c.Add(noise(rng));
  EXPECT_NEAR(c.offset_px(), 0.3, 0.05);
  int added = 8;
  while (!c.converged() && added < 200) {
    c.Add(noise(rng));
    ++added;
  }
  EXPECT_TRUE(c.converged());
  EXPECT_GE(added, DisparityOffsetCalibration::Options().converged_after_estimates);
  EXPECT_NEAR(c.offset_px(), 0.3, 0.03);
  EXPECT_EQ(c.offset_px(), c.mean_px());
  const double kept = c.offset_px();
  c.Add(5.0);  // after convergence: ignored.
  EXPECT_EQ(c.offset_px(), kept);
  EXPECT_EQ(c.num_estimates(), added);
}

// An exact rig's estimates centre on a scene-dependent bias within +-0.08 px (the rendered
// presets): below min_offset_px nothing is applied, however consistent they are.
TEST(DisparityOffsetCalibration, ASmallConsistentBiasIsNotApplied) {
  DisparityOffsetCalibration c;
  for (int i = 0; i < 100; ++i) c.Add(-0.08 + 0.001 * (i % 3));
  EXPECT_EQ(c.offset_px(), 0.0);
  EXPECT_NEAR(c.mean_px(), -0.079, 0.002);
  EXPECT_TRUE(c.converged());
}

// Windows that disagree (a large mean carried by a few wild estimates) do not set an offset:
// the mean must stand min_mean_over_sd standard deviations from zero.
TEST(DisparityOffsetCalibration, DisagreeingEstimatesAreNotApplied) {
  DisparityOffsetCalibration c;
  for (int i = 0; i < 20; ++i) c.Add(i % 4 == 0 ? 1.2 : -0.05);  // mean 0.26, sd 0.54.
  EXPECT_GT(c.mean_px(), 0.15);
  EXPECT_EQ(c.offset_px(), 0.0);
}

TEST(DisparityOffsetCalibration, IgnoresNonFiniteEstimates) {
  DisparityOffsetCalibration c;
  c.Add(std::numeric_limits<double>::quiet_NaN());
  c.Add(std::numeric_limits<double>::infinity());
  EXPECT_EQ(c.num_estimates(), 0);
  EXPECT_EQ(c.mean_px(), 0.0);
}

TEST(DisparityOffsetCalibration, OptionsAreValidated) {
  std::string why;
  EXPECT_TRUE(DisparityOffsetCalibration::Options().IsValid(&why)) << why;
  DisparityOffsetCalibration::Options o;
  o.min_estimates = 1;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("min_estimates"), std::string::npos);
  o = DisparityOffsetCalibration::Options();
  o.converged_after_estimates = 4;
  EXPECT_FALSE(o.IsValid(&why));
  o = DisparityOffsetCalibration::Options();
  o.min_offset_px = std::nan("");
  EXPECT_FALSE(o.IsValid(&why));
}

}  // namespace
}  // namespace dala
