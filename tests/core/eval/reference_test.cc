// Reference values from evo's test data (see /work/shared/data/README.md): evo and an independent
// implementation give these numbers; we must match them to ~1e-6 relative.
#include <gtest/gtest.h>

#include <string>
#include <tuple>
#include <vector>

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
  // RPE and KITTI segment errors: see the *Rpe* and *KittiSegments* tests below.
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

// RPE and KITTI segment errors against an independent numpy implementation of evo_rpe's and the
// KITTI devkit's published definitions: tests/core/eval/reference_values.py (rerun it with
// /usr/bin/python3 tests/core/eval/reference_values.py; it prints every value pinned here). It
// reproduces evo's ATE values above to all printed digits (same files, readers, association and
// Umeyama alignment). Its conventions, which are dala's documented ones (docs/evaluation.md):
//  - RPE on the aligned estimate (SE(3) cannot change it, the script checks that to 1e-10;
//    a Sim(3) scale does), pairs chosen on that estimate, rotation error in degrees;
//  - KITTI segments on the raw estimate, in double (the compiled devkit keeps distances and the
//    trace in float: on KITTI 00 that moves one segment end and r_err by ~4e-5 relative);
//  - KITTI rotations replaced by the nearest rotation (the files keep ~7 digits). dala's reader
//    used a quaternion round trip, which moved every rotation by ~1e-7 rad and the ORB RPE
//    rotation median by 1.4e-5 relative (the raw matrices agree with the nearest rotation to
//    1e-8): fixed in ReadTrajectory, which failed Kitti00OrbRpe*, medians and max.

struct RefStats {
  double rmse, mean, median, std, max;
};

void ExpectStats(const ErrorStatistics& s, const RefStats& ref, const std::string& what) {
  SCOPED_TRACE(what);
  EXPECT_REL_NEAR(s.rmse, ref.rmse, 1e-6);
  EXPECT_REL_NEAR(s.mean, ref.mean, 1e-6);
  EXPECT_REL_NEAR(s.median, ref.median, 1e-6);
  EXPECT_REL_NEAR(s.std, ref.std, 1e-6);
  EXPECT_REL_NEAR(s.max, ref.max, 1e-6);
}

struct RefRpe {
  size_t pairs;
  RefStats translation;  // Metres.
  RefStats rotation;     // Degrees.
};

void ExpectRpe(const EvalResult& r, const RefRpe& ref) {
  ASSERT_TRUE(r.ok) << r.error;
  ASSERT_TRUE(r.has_rpe);
  EXPECT_EQ(r.rpe.index_pairs.size(), ref.pairs);
  EXPECT_EQ(r.rpe.translation_errors.size(), ref.pairs);
  ExpectStats(r.rpe.translation, ref.translation, "RPE translation");
  ExpectStats(r.rpe.rotation_deg, ref.rotation, "RPE rotation");
}

struct RefKitti {
  size_t segments;
  double t_err_percent, r_err_deg_per_100m;
  // Per length 100, 200, ..., 800 m: segment count, t_err %, r_err deg/100m.
  std::vector<std::tuple<size_t, double, double>> per_length;
};

void ExpectKitti(const EvalResult& r, const RefKitti& ref) {
  ASSERT_TRUE(r.ok) << r.error;
  ASSERT_TRUE(r.has_kitti);
  EXPECT_EQ(r.kitti.segments.size(), ref.segments);
  EXPECT_REL_NEAR(r.kitti.t_err_percent, ref.t_err_percent, 1e-6);
  EXPECT_REL_NEAR(r.kitti.r_err_deg_per_100m, ref.r_err_deg_per_100m, 1e-6);
  ASSERT_EQ(r.kitti.per_length.size(), ref.per_length.size());
  for (size_t k = 0; k < ref.per_length.size(); ++k) {
    const KittiLengthError& le = r.kitti.per_length[k];
    SCOPED_TRACE("length " + std::to_string(le.length_m));
    EXPECT_EQ(le.length_m, 100.0 * static_cast<double>(k + 1));
    EXPECT_EQ(le.count, std::get<0>(ref.per_length[k]));
    EXPECT_REL_NEAR(le.t_err_percent, std::get<1>(ref.per_length[k]), 1e-6);
    EXPECT_REL_NEAR(le.r_err_deg_per_100m, std::get<2>(ref.per_length[k]), 1e-6);
  }
}

EvalResult EvaluateKitti00(const std::string& est, AlignmentType alignment, double delta,
                           DeltaUnit unit) {
  EvalOptions options;
  options.alignment = alignment;
  options.rpe_delta = delta;
  options.rpe_delta_unit = unit;
  return Evaluate(ReadTrajectory(Ref("KITTI_00_gt.txt")), ReadTrajectory(Ref(est)), options);
}

TEST(EvalReference, Kitti00OrbRpeFramesSe3) {
  DALA_SKIP_WITHOUT_SHARED_DATA("eval-reference");
  ExpectRpe(EvaluateKitti00("KITTI_00_ORB.txt", AlignmentType::kSE3, 1, DeltaUnit::kFrames),
            {4540,
             {0.0281203809269, 0.0193013154458, 0.0147090463632, 0.0204503067345, 0.302712500487},
             {0.11497352126, 0.0595834549231, 0.0410744052753, 0.0983296623115, 2.19661540694}});
}

TEST(EvalReference, Kitti00OrbRpeMetresSe3) {
  DALA_SKIP_WITHOUT_SHARED_DATA("eval-reference");
  ExpectRpe(EvaluateKitti00("KITTI_00_ORB.txt", AlignmentType::kSE3, 100, DeltaUnit::kMetres),
            {35,
             {1.10274238125, 1.00004536932, 0.895178430746, 0.464704227108, 2.29295437756},
             {0.690937263283, 0.595168823129, 0.50782345048, 0.350953520808, 1.57621097458}});
}

// The Sim(3) scale (1.00469807645) enters the RPE translations and, through the path walked
// along the scaled estimate, the 100 m pairs (36 instead of 35); rotations are unchanged at
// 1 frame.
TEST(EvalReference, Kitti00OrbRpeSim3) {
  DALA_SKIP_WITHOUT_SHARED_DATA("eval-reference");
  const EvalResult frames =
      EvaluateKitti00("KITTI_00_ORB.txt", AlignmentType::kSim3, 1, DeltaUnit::kFrames);
  EXPECT_REL_NEAR(frames.alignment.scale, 1.00469807645, 1e-9);
  ExpectRpe(frames,
            {4540,
             {0.0278224571668, 0.0189529785406, 0.0143756868896, 0.0203684493086, 0.304399856757},
             {0.11497352126, 0.0595834549231, 0.0410744052753, 0.0983296623115, 2.19661540694}});
  ExpectRpe(EvaluateKitti00("KITTI_00_ORB.txt", AlignmentType::kSim3, 100, DeltaUnit::kMetres),
            {36,
             {1.10718114848, 0.975325908905, 0.870184975166, 0.524012849999, 2.65894790364},
             {0.83753535438, 0.670171321963, 0.499763826657, 0.502330438112, 2.28725763923}});
}

// The segment errors use the raw estimate: the same numbers with any alignment.
TEST(EvalReference, Kitti00OrbKittiSegments) {
  DALA_SKIP_WITHOUT_SHARED_DATA("eval-reference");
  const RefKitti ref{3283,
                     0.69972880847,
                     0.253323364753,
                     {{445, 1.00903828924, 0.614056503992},
                      {431, 0.874378141181, 0.352636938058},
                      {424, 0.780862176135, 0.252839018319},
                      {416, 0.71887481828, 0.207213188094},
                      {408, 0.655319624081, 0.171173492421},
                      {399, 0.571992910837, 0.148580607573},
                      {385, 0.492596149585, 0.120462738736},
                      {375, 0.415861541125, 0.100037093729}}};
  for (AlignmentType alignment :
       {AlignmentType::kSE3, AlignmentType::kSim3, AlignmentType::kNone}) {
    SCOPED_TRACE(AlignmentTypeName(alignment));
    ExpectKitti(EvaluateKitti00("KITTI_00_ORB.txt", alignment, 1, DeltaUnit::kFrames), ref);
  }
}

TEST(EvalReference, Kitti00SptamRpe) {
  DALA_SKIP_WITHOUT_SHARED_DATA("eval-reference");
  ExpectRpe(EvaluateKitti00("KITTI_00_SPTAM.txt", AlignmentType::kSE3, 1, DeltaUnit::kFrames),
            {4540,
             {0.0349193727622, 0.0234064564342, 0.0191599956886, 0.0259133245898, 1.13607369686},
             {0.296389843246, 0.241716405113, 0.201018442208, 0.171522939218, 2.50355519188}});
  ExpectRpe(EvaluateKitti00("KITTI_00_SPTAM.txt", AlignmentType::kSE3, 100, DeltaUnit::kMetres),
            {36,
             {2.59686167758, 2.15043432525, 1.63426689001, 1.45578940278, 6.84964130538},
             {2.19473942637, 1.61741636004, 0.995381218671, 1.48352467722, 6.32359150797}});
}

TEST(EvalReference, Kitti00SptamKittiSegments) {
  DALA_SKIP_WITHOUT_SHARED_DATA("eval-reference");
  ExpectKitti(EvaluateKitti00("KITTI_00_SPTAM.txt", AlignmentType::kSE3, 1, DeltaUnit::kFrames),
              {3283,
               1.48696018284,
               0.557706206438,
               {{445, 2.17872343305, 1.46816760256},
                {431, 1.75092857165, 0.756148538341},
                {424, 1.58438844131, 0.528535062096},
                {416, 1.50642674288, 0.417775386734},
                {408, 1.39384327155, 0.353496589432},
                {399, 1.25790932258, 0.307334323371},
                {385, 1.09459301401, 0.26196596411},
                {375, 0.97877794434, 0.229630788442}}});
}

TEST(EvalReference, Freiburg1XyzRpe) {
  DALA_SKIP_WITHOUT_SHARED_DATA("eval-reference");
  EvalOptions options;
  options.max_time_diff_s = 0.02;
  const EvalResult r = Evaluate(ReadTrajectory(Ref("freiburg1_xyz-groundtruth.txt")),
                                ReadTrajectory(Ref("freiburg1_xyz-rgbdslam.txt")), options);
  ASSERT_TRUE(r.ok) << r.error;
  EXPECT_EQ(r.pairs.size(), 786u);
  ExpectRpe(r, {785,
                {0.00575924678224, 0.00481380044065, 0.00414074954973, 0.00316168449031,
                 0.0208658145323},
                {0.352827461257, 0.299992287226, 0.262954972396, 0.185719802451, 1.63329606233}});
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
