// The two-view motion with its essential matrix sampled twice (backend/mono/refined_two_view.h):
// on a real failure case (the correspondences of a rendered car's sharp turn, where RANSAC keeps
// a wrong motion) MAGSAC++'s is kept; on an ordinary pair RANSAC's is kept, unchanged.

#include "backend/mono/refined_two_view.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>
#include <string>

#include "backend/mono/two_view_refinement.h"
#include "tests/backend/mono/two_view_scene.h"

namespace dala {
namespace {

using testing::KittiGeometryCamera;

struct Pair {
  std::vector<Eigen::Vector2d> ref, cur;
};

// A pair of tests/backend/mono/data/ (its header says where it comes from).
Pair ReadPair(const std::string& name) {
  std::ifstream in(std::string(DALA_SOURCE_DIR) + "/tests/backend/mono/data/" + name);
  Pair pair;
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream is(line);
    double u0, v0, u1, v1;
    if (is >> u0 >> v0 >> u1 >> v1) {
      pair.ref.emplace_back(u0, v0);
      pair.cur.emplace_back(u1, v1);
    }
  }
  return pair;
}

// The rendered truth of that pair, T_cur_ref = T_w_c21^-1 T_w_c20 from the sequence's poses.txt.
Pose SharpTurnTruth() {
  Eigen::Matrix3d R;
  R << 0.988934193, -0.061595237, -0.134963659, 0.057119363, 0.997689186, -0.036792204, 0.136918008,
      0.028676031, 0.990167231;
  return MakePose(R, Eigen::Vector3d(0.357941542, -0.241783057, -0.901897337));
}

// sharp_turn_pair.txt: frames 20 -> 21 of `dala synth --preset fast --seed 3` in KITTI's
// geometry, as the frontend matched them (8.7 deg of rotation, a 0.6 m step).
TEST(RefinedTwoView, ASharpTurnKeepsMagsacsMotionWhereRansacsIsWrong) {
  const Pair pair = ReadPair("sharp_turn_pair.txt");
  ASSERT_EQ(pair.ref.size(), 440u) << "tests/backend/mono/data/sharp_turn_pair.txt not read";
  const PinholeCamera camera = KittiGeometryCamera();
  const Pose truth = SharpTurnTruth();

  // RANSAC alone, refined: the wrong basin (the failure this guards against).
  const TwoViewResult ransac = InitializeTwoView(camera, pair.ref, pair.cur, TwoViewOptions());
  ASSERT_TRUE(ransac.ok) << ransac.reason;
  Pose T_ransac = ransac.T_cur_ref;
  std::vector<std::optional<Eigen::Vector3d>> p = ransac.p_ref;
  RefineTwoView(camera, pair.ref, pair.cur, 1.0, 20, &T_ransac, &p);
  EXPECT_GT(TravelAngleDeg(T_ransac, truth), 30.0);

  const RefinedTwoView solved = SolveRefinedTwoView(camera, pair.ref, pair.cur, TwoViewOptions(),
                                                    /*refine=*/true);
  ASSERT_TRUE(solved.two_view.ok) << solved.two_view.reason;
  EXPECT_TRUE(solved.magsac);
  EXPECT_LT(TravelAngleDeg(solved.T_cur_ref, truth), 2.0);
  EXPECT_LT(LogSO3(solved.T_cur_ref.linear().transpose() * truth.linear()).norm() * 180.0 / M_PI,
            0.2);
  EXPECT_GT(EpipolarScore(camera, solved.T_cur_ref, pair.ref, pair.cur, 1.0),
            EpipolarScore(camera, T_ransac, pair.ref, pair.cur, 1.0));
}

// few_points_pair.txt: frames 100 -> 103 of `dala synth --preset fast --seed 5` in KITTI's
// geometry, 53 correspondences bunched in the left half of the image (the truth: 5 deg of rotation,
// a 3.2 m step forward). RANSAC's motion (51 points triangulated) turns 31 deg and moves sideways;
// MAGSAC++'s is 69 deg from it and triangulates only 40. Two motions fit and neither is sure:
// the pair is refused, and the initialiser waits for the next frame.
TEST(RefinedTwoView, TwoMotionsThatFitFewPointsAreRefused) {
  const Pair pair = ReadPair("few_points_pair.txt");
  ASSERT_EQ(pair.ref.size(), 53u) << "tests/backend/mono/data/few_points_pair.txt not read";
  const PinholeCamera camera = KittiGeometryCamera();
  const TwoViewResult ransac = InitializeTwoView(camera, pair.ref, pair.cur, TwoViewOptions());
  ASSERT_TRUE(ransac.ok) << ransac.reason;  // Alone, RANSAC would start the map from it.
  const RefinedTwoView solved = SolveRefinedTwoView(camera, pair.ref, pair.cur, TwoViewOptions(),
                                                    /*refine=*/true);
  EXPECT_FALSE(solved.two_view.ok);
  EXPECT_EQ(solved.two_view.reason.rfind("two motions fit: MAGSAC++'s direction of travel is", 0),
            0u)
      << solved.two_view.reason;
}

TEST(RefinedTwoView, AnOrdinaryPairKeepsRansacsMotionBitForBit) {
  // A general scene, 300 points at 4-12 m, a 0.5 m step with 5 deg of rotation, 0.5 px noise.
  const PinholeCamera camera = KittiGeometryCamera();
  const Pose T_cur_ref =
      MakePose(ExpSO3(Eigen::Vector3d(0.02, -0.08, 0.01)), Eigen::Vector3d(-0.5, 0.05, -0.2));
  const testing::TwoViews pair = testing::RenderTwoViews(camera, T_cur_ref, false, 0.5, 3);
  const TwoViewResult ransac = InitializeTwoView(camera, pair.ref, pair.cur, TwoViewOptions());
  ASSERT_TRUE(ransac.ok) << ransac.reason;
  Pose T_ransac = ransac.T_cur_ref;
  std::vector<std::optional<Eigen::Vector3d>> p = ransac.p_ref;
  RefineTwoView(camera, pair.ref, pair.cur, 1.0, 20, &T_ransac, &p);

  const RefinedTwoView solved = SolveRefinedTwoView(camera, pair.ref, pair.cur, TwoViewOptions(),
                                                    /*refine=*/true);
  ASSERT_TRUE(solved.two_view.ok) << solved.two_view.reason;
  EXPECT_FALSE(solved.magsac);
  EXPECT_TRUE(solved.T_cur_ref.matrix() == T_ransac.matrix());
  EXPECT_LT(TravelAngleDeg(solved.T_cur_ref, T_cur_ref), 2.0);
}

}  // namespace
}  // namespace dala
