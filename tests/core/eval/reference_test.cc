// Reference values from evo's test data (see /work/shared/data/README.md): evo and an independent
// implementation give these numbers; we must match them to ~1e-6 relative.
#include <gtest/gtest.h>

#include "core/eval/evaluate.h"
#include "core/io/trajectory_io.h"
#include "tests/test_util.h"

namespace dala {
namespace {

std::string Ref(const std::string& name) {
  return testing::SharedDataDir() + "/eval-reference/" + name;
}

#define EXPECT_REL_NEAR(actual, expected, rel) \
  EXPECT_NEAR((actual), (expected), std::abs(expected) * (rel))

TEST(EvalReference, Kitti00OrbSe3) {
  DALA_SKIP_WITHOUT_SHARED_DATA("eval-reference");
  const Trajectory gt = ReadTrajectory(Ref("KITTI_00_gt.txt"));
  const Trajectory est = ReadTrajectory(Ref("KITTI_00_ORB.txt"));
  EvalOptions options;
  options.alignment = AlignmentType::kSE3;
  const EvalResult r = Evaluate(gt, est, options);
  ASSERT_TRUE(r.ok) << r.error;
  EXPECT_EQ(r.pairs.size(), 4541u);
  EXPECT_TRUE(r.pairs.by_index);
  EXPECT_REL_NEAR(r.ate.translation.rmse, 1.3034497146, 1e-6);
  EXPECT_REL_NEAR(r.ate.translation.mean, 1.1569971285, 1e-6);
  EXPECT_REL_NEAR(r.ate.translation.median, 1.0656247696, 1e-6);
  EXPECT_REL_NEAR(r.ate.translation.max, 3.5879491207, 1e-6);
  EXPECT_DOUBLE_EQ(r.alignment.scale, 1.0);
  // KITTI 00 is 3.7 km long: segment errors exist; ORB-SLAM2 stereo scores ~1% on it.
  ASSERT_TRUE(r.has_kitti);
  EXPECT_GT(r.kitti.t_err_percent, 0.2);
  EXPECT_LT(r.kitti.t_err_percent, 3.0);
  std::cout << "ORB kitti t_err " << r.kitti.t_err_percent << " % r_err "
            << r.kitti.r_err_deg_per_100m << " deg/100m, rpe trans rmse " << r.rpe.translation.rmse
            << "\n";
}

TEST(EvalReference, Kitti00SptamSe3) {
  DALA_SKIP_WITHOUT_SHARED_DATA("eval-reference");
  const EvalResult r = Evaluate(ReadTrajectory(Ref("KITTI_00_gt.txt")),
                                ReadTrajectory(Ref("KITTI_00_SPTAM.txt")), EvalOptions());
  ASSERT_TRUE(r.ok) << r.error;
  EXPECT_REL_NEAR(r.ate.translation.rmse, 3.7384879076, 1e-6);
  EXPECT_REL_NEAR(r.ate.translation.mean, 3.4909766331, 1e-6);
}

TEST(EvalReference, Kitti00OrbSim3) {
  DALA_SKIP_WITHOUT_SHARED_DATA("eval-reference");
  EvalOptions options;
  options.alignment = AlignmentType::kSim3;
  const EvalResult r = Evaluate(ReadTrajectory(Ref("KITTI_00_gt.txt")),
                                ReadTrajectory(Ref("KITTI_00_ORB.txt")), options);
  ASSERT_TRUE(r.ok) << r.error;
  EXPECT_REL_NEAR(r.ate.translation.rmse, 0.9377090736, 1e-6);
  EXPECT_NEAR(r.alignment.scale, 1.004698, 1e-6);
}

TEST(EvalReference, Freiburg1XyzTum) {
  DALA_SKIP_WITHOUT_SHARED_DATA("eval-reference");
  EvalOptions options;
  options.max_time_diff_s = 0.02;
  const EvalResult r = Evaluate(ReadTrajectory(Ref("freiburg1_xyz-groundtruth.txt")),
                                ReadTrajectory(Ref("freiburg1_xyz-rgbdslam.txt")), options);
  ASSERT_TRUE(r.ok) << r.error;
  EXPECT_FALSE(r.pairs.by_index);
  EXPECT_EQ(r.pairs.size(), 786u);
  EXPECT_REL_NEAR(r.ate.translation.rmse, 0.0134734678, 1e-6);
  EXPECT_FALSE(r.has_kitti);  // Under 100 m of path.
}

// The data README calls V102.txt "the same ground truth" as V102_groundtruth.csv, but the files
// differ: V102.txt (TUM, 10 Hz) starts in another world frame, ends 0.9 s after the ground truth
// and, after SE(3) alignment, is 9 cm off with 2.7 deg of rotation error: it is an estimate. So
// this checks the EuRoC csv against a TUM file through time association, with our own values
// (pinned loosely: no independent reference value exists for this pair).
TEST(EvalReference, V102EurocCsvAgainstTum) {
  DALA_SKIP_WITHOUT_SHARED_DATA("eval-reference");
  const Trajectory csv = ReadTrajectory(Ref("V102_groundtruth.csv"));
  const Trajectory tum = ReadTrajectory(Ref("V102.txt"));
  EXPECT_EQ(tum.size(), 807u);
  const EvalResult r = Evaluate(csv, tum, EvalOptions());
  ASSERT_TRUE(r.ok) << r.error;
  EXPECT_EQ(r.pairs.size(), 798u);  // The last 9 estimate poses are past the ground truth.
  EXPECT_NEAR(r.ate.translation.rmse, 0.0917, 5e-4);
  EXPECT_NEAR(r.gt_path_length_m, 75.65, 0.01);
  // The ground truth against itself is exact.
  const EvalResult self = Evaluate(csv, csv, EvalOptions());
  ASSERT_TRUE(self.ok);
  EXPECT_EQ(self.pairs.size(), csv.size());
  EXPECT_LT(self.ate.translation.max, 1e-9);
}

}  // namespace
}  // namespace dala
