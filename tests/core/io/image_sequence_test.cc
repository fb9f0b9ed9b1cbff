#include "core/io/image_sequence.h"

#include <gtest/gtest.h>

#include "tests/test_util.h"

namespace dala {
namespace {

TEST(GroundTruthAtTimes, InterpolatesInsideAndRefusesOutsideOrAcrossGaps) {
  Trajectory gt;
  const Pose A = MakePose(Eigen::Matrix3d::Identity(), Eigen::Vector3d(0, 0, 0));
  const Pose B = MakePose(ExpSO3(Eigen::Vector3d(0, 0, 0.2)), Eigen::Vector3d(2, 0, 0));
  gt.Add(1000000000, A);
  gt.Add(1100000000, B);
  gt.Add(2100000000, A);  // A 1 s gap.
  const std::vector<int64_t> t = {500000000,  999500000,  1000000000, 1025000000,
                                  1100000000, 1600000000, 2100000000, 2102000000};
  const auto out = GroundTruthAtTimes(gt, t, 200000000);
  ASSERT_EQ(out.size(), t.size());
  EXPECT_FALSE(out[0].has_value());  // Before.
  ASSERT_TRUE(out[1].has_value());   // 0.5 ms before the first sample: within the tolerance.
  EXPECT_POSE_NEAR(*out[1], A, 1e-12);
  ASSERT_TRUE(out[2].has_value());
  EXPECT_POSE_NEAR(*out[2], A, 1e-12);
  ASSERT_TRUE(out[3].has_value());
  EXPECT_POSE_NEAR(*out[3], InterpolatePose(A, B, 0.25), 1e-12);
  EXPECT_NEAR(out[3]->translation().x(), 0.5, 1e-12);
  ASSERT_TRUE(out[4].has_value());
  EXPECT_POSE_NEAR(*out[4], B, 1e-12);
  EXPECT_FALSE(out[5].has_value());  // Inside the 1 s gap.
  ASSERT_TRUE(out[6].has_value());
  EXPECT_FALSE(out[7].has_value());  // 2 ms after the end.
  EXPECT_TRUE(GroundTruthAtTimes(Trajectory(), t, 1)[3] == std::nullopt);
}

}  // namespace
}  // namespace dala
