#include "core/io/trajectory_io.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <random>

#include "core/error.h"
#include "core/io/text_lines.h"
#include "tests/test_util.h"

namespace dala {
namespace {

using ::testing::HasSubstr;

void WriteText(const std::string& path, const std::string& text) {
  std::ofstream os(path);
  os << text;
}

Trajectory RandomTrajectory(int n) {
  std::mt19937 rng(7);
  Trajectory t;
  for (int i = 0; i < n; ++i)
    t.Add(1403715524907143168LL + i * 50000000LL, testing::RandomPose(rng));
  return t;
}

TEST(TrajectoryIo, TumRoundTrip) {
  testing::TempDir dir;
  const Trajectory t = RandomTrajectory(20);
  WriteTrajectoryTum(dir / "t.txt", t);
  EXPECT_EQ(DetectTrajectoryFormat(dir / "t.txt"), TrajectoryFormat::kTum);
  const Trajectory r = ReadTrajectory(dir / "t.txt");
  ASSERT_EQ(r.size(), t.size());
  EXPECT_TRUE(r.has_timestamps);
  for (size_t i = 0; i < t.size(); ++i) {
    EXPECT_EQ(r.poses[i].t_ns, t.poses[i].t_ns);
    EXPECT_POSE_NEAR(r.poses[i].T_w_c, t.poses[i].T_w_c, 1e-7);
  }
}

// Times between -1 s and 0 keep their sign (written as positive, the reader would refuse the
// file as going back in time).
TEST(TrajectoryIo, TumKeepsTheSignOfTimesBetweenMinusOneAndZero) {
  testing::TempDir dir;
  Trajectory t;
  for (const int64_t t_ns : {-1500000000LL, -999999999LL, -500000000LL, -1LL, 0LL, 250000000LL}) {
    t.Add(t_ns, Pose::Identity());
  }
  WriteTrajectoryTum(dir / "t.txt", t);
  const Trajectory r = ReadTrajectory(dir / "t.txt");
  ASSERT_EQ(r.size(), t.size());
  for (size_t i = 0; i < t.size(); ++i) EXPECT_EQ(r.poses[i].t_ns, t.poses[i].t_ns) << i;
}

TEST(TrajectoryIo, KittiRoundTripAndTimes) {
  testing::TempDir dir;
  const Trajectory t = RandomTrajectory(5);
  WriteTrajectoryKitti(dir / "k.txt", t);
  EXPECT_EQ(DetectTrajectoryFormat(dir / "k.txt"), TrajectoryFormat::kKitti);
  Trajectory r = ReadTrajectory(dir / "k.txt");
  ASSERT_EQ(r.size(), 5u);
  EXPECT_FALSE(r.has_timestamps);
  EXPECT_EQ(r.poses[3].t_ns, 3000000000LL);
  for (size_t i = 0; i < t.size(); ++i) EXPECT_POSE_NEAR(r.poses[i].T_w_c, t.poses[i].T_w_c, 1e-7);
  WriteText(dir / "times.txt", "0.0\n0.1\n0.2\n0.3\n0.4\n");
  ApplyTimes(dir / "times.txt", &r);
  EXPECT_TRUE(r.has_timestamps);
  EXPECT_EQ(r.poses[4].t_ns, 400000000LL);
  WriteText(dir / "short.txt", "0.0\n0.1\n");
  EXPECT_THROW(ApplyTimes(dir / "short.txt", &r), Error);
}

TEST(TrajectoryIo, EurocCsvReadsWxyzOrder) {
  testing::TempDir dir;
  WriteText(dir / "gt.csv",
            "#timestamp, p_x, p_y, p_z, q_w, q_x, q_y, q_z\n"
            "1000,1,2,3,0.7071067811865476,0,0,0.7071067811865476,9,9\n"
            "2000,1,2,4,1,0,0,0\n"
            "1403715524907143168,1,2,4,1,0,0,0\n");
  EXPECT_EQ(DetectTrajectoryFormat(dir / "gt.csv"), TrajectoryFormat::kEurocCsv);
  const Trajectory r = ReadTrajectory(dir / "gt.csv");
  ASSERT_EQ(r.size(), 3u);
  EXPECT_EQ(r.poses[0].t_ns, 1000);
  EXPECT_EQ(r.poses[2].t_ns, 1403715524907143168LL);  // Exact: no double round trip.
  EXPECT_NEAR(LogSO3(r.poses[0].T_w_c.linear()).z(), M_PI / 2, 1e-9);
}

TEST(TrajectoryIo, ErrorsNameFileAndLine) {
  testing::TempDir dir;
  const auto expect_error = [&](const std::string& text, const std::string& what) {
    WriteText(dir / "bad.txt", text);
    try {
      ReadTrajectory(dir / "bad.txt", TrajectoryFormat::kTum);
      ADD_FAILURE() << "no error for: " << text;
    } catch (const Error& e) {
      EXPECT_THAT(e.what(), HasSubstr("bad.txt"));
      EXPECT_THAT(e.what(), HasSubstr(what)) << e.what();
    }
  };
  expect_error("1 0 0 0 0 0 0 1\n2 0 0 0 0 0 1\n", ":2: expected 8 columns");
  expect_error("2 0 0 0 0 0 0 1\n1 0 0 0 0 0 0 1\n", ":2: timestamp");
  expect_error("1 0 0 0 0 0 0 1\n2 0 x 0 0 0 0 1\n", ":2: 'x' is not a finite number");
  expect_error("1 0 0 0 0 0 0 3\n", ":1: quaternion norm");
  expect_error("# nothing\n", "no trajectory");
  EXPECT_THROW(ReadTrajectory(dir / "missing.txt"), Error);
  try {
    ReadTrajectory(dir / "missing.txt");
  } catch (const Error& e) {
    EXPECT_THAT(e.what(), HasSubstr("missing file"));
  }
}

TEST(TrajectoryIo, KittiRejectsNonRotation) {
  testing::TempDir dir;
  WriteText(dir / "k.txt", "2 0 0 0 0 1 0 0 0 0 1 0\n");
  EXPECT_THROW(ReadTrajectory(dir / "k.txt"), Error);
}

// A KITTI row keeps ~7 digits: the diagonal rounding (a symmetric perturbation R (I + S)) must not
// move the rotation read, which is the nearest rotation, exactly R here. (The former quaternion
// round trip moved it by ~1e-7 rad and the KITTI 00 RPE rotation median by 1.4e-5 relative.)
TEST(TrajectoryIo, KittiRotationIsTheNearestRotation) {
  testing::TempDir dir;
  const Eigen::Matrix3d R = ExpSO3(Eigen::Vector3d(0.3, -0.8, 1.1));
  const Eigen::Matrix3d S = Eigen::Vector3d(4e-7, -3e-7, 2e-7).asDiagonal();
  const Eigen::Matrix3d M = R * (Eigen::Matrix3d::Identity() + S);
  char row[512];
  std::snprintf(row, sizeof(row), "%.17g %.17g %.17g 1 %.17g %.17g %.17g 2 %.17g %.17g %.17g 3\n",
                M(0, 0), M(0, 1), M(0, 2), M(1, 0), M(1, 1), M(1, 2), M(2, 0), M(2, 1), M(2, 2));
  WriteText(dir / "k.txt", row);
  const Trajectory t = ReadTrajectory(dir / "k.txt");
  ASSERT_EQ(t.size(), 1u);
  EXPECT_LT(LogSO3(R.transpose() * t.poses[0].T_w_c.linear()).norm(), 1e-14);
  EXPECT_EQ(t.poses[0].T_w_c.translation(), Eigen::Vector3d(1, 2, 3));
}

TEST(TrajectoryIo, WriterIsAtomicOnFailure) {
  testing::TempDir dir;
  EXPECT_THROW(WriteTrajectoryTum(dir / "no/such/folder/t.txt", RandomTrajectory(3)), Error);
}

TEST(TrajectoryIo, ReadsSharedReferenceFiles) {
  DALA_SKIP_WITHOUT_SHARED_DATA("eval-reference");
  const std::string d = testing::SharedDataDir() + "/eval-reference/";
  EXPECT_EQ(ReadTrajectory(d + "KITTI_00_gt.txt").size(), 4541u);
  const Trajectory euroc = ReadTrajectory(d + "V102_groundtruth.csv");
  const Trajectory tum = ReadTrajectory(d + "V102.txt");
  EXPECT_GT(euroc.size(), 100u);
  EXPECT_GT(tum.size(), 100u);
  EXPECT_GT(ReadTrajectory(d + "freiburg1_xyz-groundtruth.txt").size(), 100u);
}

}  // namespace
}  // namespace dala

namespace dala {
namespace {
TEST(TrajectoryIo, ParsesSecondsExactly) {
  EXPECT_EQ(ParseSecondsAsNs("f", 1, "1.403715572212143183e+09"), 1403715572212143183LL);
  EXPECT_EQ(ParseSecondsAsNs("f", 1, "1403715572.212143183"), 1403715572212143183LL);
  EXPECT_EQ(ParseSecondsAsNs("f", 1, "0.1"), 100000000LL);
  EXPECT_EQ(ParseSecondsAsNs("f", 1, "1.000000e-01"), 100000000LL);
  EXPECT_EQ(ParseSecondsAsNs("f", 1, "12"), 12000000000LL);
  EXPECT_EQ(ParseSecondsAsNs("f", 1, "0.0000000016"), 2LL);
  EXPECT_THROW(ParseSecondsAsNs("f", 1, "1.2.3"), Error);
  EXPECT_THROW(ParseSecondsAsNs("f", 1, "abc"), Error);
}
}  // namespace
}  // namespace dala
