#include "backend/ba/disparity_offset_calibration.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

namespace dala {
namespace {

// Estimates of a rig with a real offset (KITTI-like: ~0.3 px, windows agreeing to ~0.05 px):
// the offset is used from the min_estimates-th estimate on, is the median, and the calibration
// stops once that median is stable.
TEST(DisparityOffsetCalibration, AppliesAClearOffsetAndConverges) {
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
  EXPECT_EQ(c.offset_px(), c.median_px()) << "beyond twice the bias the weight is 1";
  EXPECT_EQ(c.weight(), 1.0);
  const double kept = c.offset_px();
  c.Add(5.0);  // after convergence: ignored.
  EXPECT_EQ(c.offset_px(), kept);
  EXPECT_EQ(c.num_estimates(), added);
}

// An exact rig's estimates centre on zero within a scene-dependent bias (rendered presets:
// |median| <= 0.055 px): within bias_px nothing is applied, however consistent they are.
TEST(DisparityOffsetCalibration, AnExactRigsBiasIsNotApplied) {
  DisparityOffsetCalibration c;
  for (int i = 0; i < 100; ++i) c.Add(-0.06 + 0.001 * (i % 3));
  EXPECT_EQ(c.offset_px(), 0.0);
  EXPECT_FALSE(std::signbit(c.offset_px())) << "0, not -0 (the report prints it)";
  EXPECT_NEAR(c.median_px(), -0.059, 0.002);
  EXPECT_TRUE(c.converged());
}

// The weight is continuous in the median: no value of the median (or of bias_px) at which the
// offset jumps. Between bias and twice the bias it ramps linearly.
TEST(DisparityOffsetCalibration, TheWeightRampsWithoutAStep) {
  DisparityOffsetCalibration::Options o;
  o.min_estimates = 2;
  double last = 0.0;
  for (double m = 0.0; m <= 0.3 + 1e-12; m += 0.005) {
    DisparityOffsetCalibration c(o);
    c.Add(m);
    c.Add(m);
    const double expected = m <= o.bias_px         ? 0.0
                            : m >= 2.0 * o.bias_px ? m
                                                   : m * (m - o.bias_px) / o.bias_px;
    EXPECT_NEAR(c.offset_px(), expected, 1e-12) << "median " << m;
    EXPECT_LE(c.offset_px() - last, 0.005 * 3.0 + 1e-12) << "a step at median " << m;
    last = c.offset_px();
  }
  DisparityOffsetCalibration negative(o);
  negative.Add(-0.3);
  negative.Add(-0.3);
  EXPECT_DOUBLE_EQ(negative.offset_px(), -0.3);
}

// Windows that disagree (a large mean carried by a few wild estimates) do not set an offset: the
// median is not moved by them.
TEST(DisparityOffsetCalibration, AFewWildEstimatesDoNotSetAnOffset) {
  DisparityOffsetCalibration c;
  for (int i = 0; i < 20; ++i) c.Add(i % 4 == 0 ? 1.2 : -0.05);  // mean 0.26, median -0.05.
  EXPECT_DOUBLE_EQ(c.median_px(), -0.05);
  EXPECT_EQ(c.offset_px(), 0.0);
}

// KITTI 06 from start frame 5 (the per-window estimates of that run, --v=2): they scatter with
// the scene (0.07-0.32 px, sd 0.065), which a gate on the mean against 3 sd never passed; the
// median is used.
TEST(DisparityOffsetCalibration, ScatteredEstimatesOfARealRigAreUsed) {
  const double estimates[] = {0.324, 0.268, 0.197, 0.109, 0.126, 0.139, 0.183, 0.125,
                              0.094, 0.074, 0.160, 0.166, 0.145, 0.168, 0.174, 0.230,
                              0.274, 0.247, 0.224, 0.234, 0.272, 0.267, 0.171};
  DisparityOffsetCalibration c;
  for (double e : estimates) c.Add(e);
  EXPECT_NEAR(c.median_px(), 0.174, 1e-9);
  EXPECT_NEAR(c.offset_px(), 0.174, 1e-9);
}

TEST(DisparityOffsetCalibration, IgnoresNonFiniteEstimates) {
  DisparityOffsetCalibration c;
  c.Add(std::numeric_limits<double>::quiet_NaN());
  c.Add(std::numeric_limits<double>::infinity());
  EXPECT_EQ(c.num_estimates(), 0);
  EXPECT_EQ(c.median_px(), 0.0);
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
  o.bias_px = std::nan("");
  EXPECT_FALSE(o.IsValid(&why));
}

}  // namespace
}  // namespace dala
