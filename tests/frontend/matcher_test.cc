#include "frontend/matcher.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "frontend/harris.h"
#include "frontend/match_geometry.h"
#include "tests/frontend/test_images.h"
#include "tests/test_util.h"

namespace dala {
namespace {

using testing::ApplyH;
using testing::MakeTexturedImage;
using testing::SimilarityAboutCentre;
using testing::Warp;

struct Quality {
  int matches = 0;
  int correct = 0;
  double precision() const { return matches > 0 ? static_cast<double>(correct) / matches : 0.0; }
};

Quality Evaluate(const DetectedImage& a, const DetectedImage& b, const std::vector<Match>& m,
                 const cv::Mat& H) {
  Quality q;
  q.matches = static_cast<int>(m.size());
  for (const Match& x : m) {
    if ((ApplyH(H, a.points[x.i].uv) - b.points[x.j].uv).norm() < 3.0) ++q.correct;
  }
  return q;
}

void ExpectOneToOne(const std::vector<Match>& m, size_t na, size_t nb) {
  std::vector<bool> ua(na, false), ub(nb, false);
  for (size_t k = 0; k < m.size(); ++k) {
    ASSERT_TRUE(m[k].i >= 0 && m[k].i < static_cast<int>(na));
    ASSERT_TRUE(m[k].j >= 0 && m[k].j < static_cast<int>(nb));
    ASSERT_FALSE(ua[m[k].i]) << "A point matched twice";
    ASSERT_FALSE(ub[m[k].j]) << "B point matched twice";
    ua[m[k].i] = ub[m[k].j] = true;
    if (k > 0) {
      ASSERT_LT(m[k - 1].i, m[k].i) << "matches must be sorted by i";
    }
  }
}

class MatcherSweepTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    image_ = new cv::Mat(MakeTexturedImage(640, 480, 7));
    a_ = new DetectedImage(DetectHarris(*image_, HarrisOptions()));
  }
  static void TearDownTestSuite() {
    delete a_;
    delete image_;
  }
  // Matches A with A warped by H, with and without the homography check.
  void Check(const cv::Mat& H, int min_correct, const std::string& what) {
    const DetectedImage b = DetectHarris(Warp(*image_, H), HarrisOptions());
    for (GeometricCheck check : {GeometricCheck::kNone, GeometricCheck::kHomography}) {
      MatcherOptions o;
      o.geometric_check = check;
      MatchStats stats;
      const std::vector<Match> m = MatchPoints(*a_, b, o, nullptr, &stats);
      ExpectOneToOne(m, a_->points.size(), b.points.size());
      const Quality q = Evaluate(*a_, b, m, H);
      const std::string label = what + (check == GeometricCheck::kNone ? " no check" : " H check");
      EXPECT_GT(q.precision(), 0.95) << label << ": " << q.correct << "/" << q.matches;
      EXPECT_GE(q.correct, min_correct) << label;
      EXPECT_EQ(stats.after_check, q.matches);
      EXPECT_EQ(stats.confirmed + stats.propagated >= stats.after_check, true);
    }
  }
  static cv::Mat* image_;
  static DetectedImage* a_;
};
cv::Mat* MatcherSweepTest::image_ = nullptr;
DetectedImage* MatcherSweepTest::a_ = nullptr;

// Bounds on correct matches: ~75 % of what the matcher finds at writing (2012, 1485, 1394, 1282,
// 1389, 1869 for the rotations; 1045, 713, 278 for the scales), so that a regression fails.
TEST_F(MatcherSweepTest, RotationSweep) {
  const std::pair<double, int> cases[] = {{0, 1500}, {30, 1110},  {60, 1040},
                                          {90, 960}, {135, 1040}, {180, 1400}};
  for (const auto& [deg, min_correct] : cases) {
    Check(SimilarityAboutCentre(image_->size(), deg * M_PI / 180.0, 1.0), min_correct,
          "rotation " + std::to_string(deg));
  }
}

TEST_F(MatcherSweepTest, ScaleSweep) {
  const std::pair<double, int> cases[] = {{1.25, 780}, {1.5, 530}, {2.0, 200}};
  for (const auto& [scale, min_correct] : cases) {
    Check(SimilarityAboutCentre(image_->size(), 0.0, scale), min_correct,
          "scale " + std::to_string(scale));
  }
}

TEST_F(MatcherSweepTest, RotationWithScale) {
  Check(SimilarityAboutCentre(image_->size(), 2.3, 1.6), 450,
        "rotation 132 deg, scale 1.6");  // 602 at writing
  // The inverse direction: B is A zoomed out.
  Check(SimilarityAboutCentre(image_->size(), -0.7, 1.0 / 1.5), 630,
        "rotation -40 deg, 1/1.5");  // 840 at writing
}

TEST(MatcherTest, UnrelatedImagesGiveAlmostNothing) {
  const DetectedImage a = DetectHarris(MakeTexturedImage(640, 480, 101), HarrisOptions());
  const DetectedImage b = DetectHarris(MakeTexturedImage(640, 480, 202), HarrisOptions());
  const std::vector<Match> m = MatchPoints(a, b, MatcherOptions());
  EXPECT_LT(m.size(), 15u);  // 2000 points each side; 6 at writing.
}

TEST(MatcherTest, StereoPriorOnHorizontallyShiftedPair) {
  const cv::Mat left = MakeTexturedImage(640, 480, 31);
  const double disparity = 12.3;
  // right(x, y) = left(x + disparity, y): a point at u in left is at u - disparity in right.
  const cv::Mat H = (cv::Mat_<double>(3, 3) << 1, 0, -disparity, 0, 1, 0, 0, 0, 1);
  const cv::Mat right = Warp(left, H);
  const DetectedImage a = DetectHarris(left, HarrisOptions());
  const DetectedImage b = DetectHarris(right, HarrisOptions());
  const MatchPrior prior = MatchPrior::RectifiedStereo(1.5, 0.0, 40.0);
  const std::vector<Match> m = MatchPoints(a, b, MatcherOptions::ForStereo(), &prior);
  ExpectOneToOne(m, a.points.size(), b.points.size());
  const Quality q = Evaluate(a, b, m, H);
  EXPECT_GT(q.correct, 1000);
  EXPECT_GT(q.precision(), 0.99);
  for (const Match& x : m) {
    const Eigen::Vector2d d = a.points[x.i].uv - b.points[x.j].uv;
    ASSERT_LE(std::abs(d.y()), 1.5);
    ASSERT_TRUE(d.x() >= 0.0 && d.x() <= 40.0);
  }
  // A disparity band that excludes the true disparity leaves (almost) nothing.
  const MatchPrior wrong = MatchPrior::RectifiedStereo(1.5, 20.0, 60.0);
  EXPECT_LT(MatchPoints(a, b, MatcherOptions::ForStereo(), &wrong).size(), 10u);
}

TEST(MatcherTest, PredictedPriorGuidesAndRestricts) {
  const cv::Mat img = MakeTexturedImage(640, 480, 41);
  const cv::Mat H = SimilarityAboutCentre(img.size(), 0.15, 1.1);
  const DetectedImage a = DetectHarris(img, HarrisOptions());
  const DetectedImage b = DetectHarris(Warp(img, H), HarrisOptions());
  std::vector<Eigen::Vector2d> predicted;
  for (const auto& p : a.points) predicted.push_back(ApplyH(H, p.uv) + Eigen::Vector2d(4.0, -3.0));
  const MatchPrior prior = MatchPrior::Predicted(predicted, 10.0);
  const std::vector<Match> m = MatchPoints(a, b, MatcherOptions::ForTracking(), &prior);
  const Quality q = Evaluate(a, b, m, H);
  EXPECT_GT(q.correct, 600);
  EXPECT_GT(q.precision(), 0.98);
  for (const Match& x : m) ASSERT_LE((b.points[x.j].uv - predicted[x.i]).norm(), 10.0);
  // Unknown predictions (NaN) allow nothing.
  const MatchPrior none = MatchPrior::Predicted(
      std::vector<Eigen::Vector2d>(
          a.points.size(), Eigen::Vector2d::Constant(std::numeric_limits<double>::quiet_NaN())),
      10.0);
  EXPECT_TRUE(MatchPoints(a, b, MatcherOptions::ForTracking(), &none).empty());
}

TEST(MatcherTest, PriorOfWrongSizeDies) {
  const DetectedImage a = DetectHarris(MakeTexturedImage(320, 240, 1), HarrisOptions());
  const MatchPrior prior = MatchPrior::Predicted({Eigen::Vector2d(1, 1)}, 5.0);
  EXPECT_DEATH(MatchPoints(a, a, MatcherOptions(), &prior), "predicted_uv");
}

TEST(MatcherTest, Deterministic) {
  const cv::Mat img = MakeTexturedImage(640, 480, 51);
  const cv::Mat H = SimilarityAboutCentre(img.size(), 1.0, 1.3, 2e-4, 1e-4);
  const DetectedImage a = DetectHarris(img, HarrisOptions());
  const DetectedImage b = DetectHarris(Warp(img, H), HarrisOptions());
  for (GeometricCheck check :
       {GeometricCheck::kNone, GeometricCheck::kHomography, GeometricCheck::kFundamental}) {
    MatcherOptions o;
    o.geometric_check = check;
    const std::vector<Match> m1 = MatchPoints(a, b, o);
    cv::theRNG() = cv::RNG(12345);  // The caller's RNG state must not matter.
    const std::vector<Match> m2 = MatchPoints(a, b, o);
    ASSERT_EQ(m1.size(), m2.size());
    ASSERT_GT(m1.size(), 100u);
    for (size_t k = 0; k < m1.size(); ++k) {
      EXPECT_EQ(m1[k].i, m2[k].i);
      EXPECT_EQ(m1[k].j, m2[k].j);
      EXPECT_EQ(m1[k].score, m2[k].score);
    }
  }
}

TEST(MatcherTest, EmptyInputsGiveEmptyResult) {
  const DetectedImage a = DetectHarris(MakeTexturedImage(320, 240, 2), HarrisOptions());
  const DetectedImage flat =
      DetectHarris(cv::Mat(240, 320, CV_8UC1, cv::Scalar(7)), HarrisOptions());
  EXPECT_TRUE(MatchPoints(a, flat, MatcherOptions()).empty());
  EXPECT_TRUE(MatchPoints(flat, a, MatcherOptions()).empty());
}

TEST(MatcherOptionsTest, ValidationNamesTheOption) {
  std::string why;
  EXPECT_TRUE(MatcherOptions().IsValid(&why)) << why;
  EXPECT_TRUE(MatcherOptions::ForStereo().IsValid(&why)) << why;
  EXPECT_TRUE(MatcherOptions::ForTracking().IsValid(&why)) << why;
  MatcherOptions o;
  o.min_zncc = 1.5;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("min_zncc"), std::string::npos);
  o = MatcherOptions();
  o.min_disparity = 10;
  o.max_disparity = 5;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("disparity"), std::string::npos);
  o = MatcherOptions();
  o.top_k = 0;
  EXPECT_FALSE(o.IsValid(&why));
}

TEST(MatchGeometryTest, EpipolarAndRansacChecks) {
  DetectedImage a, b;
  // Ten true correspondences of a pure translation (-5, 0) and two outliers.
  for (int k = 0; k < 12; ++k) {
    InterestPoint p, q;
    p.uv = Eigen::Vector2d(20.0 + 37.0 * k, 10.0 + 23.0 * ((k * 7) % 11));
    q.uv = p.uv - Eigen::Vector2d(5.0, 0.0);
    if (k == 3) q.uv += Eigen::Vector2d(0.0, 9.0);    // Off the epipolar line.
    if (k == 8) q.uv += Eigen::Vector2d(60.0, 40.0);  // Wrong everywhere.
    a.points.push_back(p);
    b.points.push_back(q);
  }
  std::vector<Match> m;
  for (int k = 0; k < 12; ++k) m.push_back({k, k, 0.9f});
  MatcherOptions o;
  o.geometric_check = GeometricCheck::kEpipolarRectified;
  o.epipolar_max_dv = 1.0;
  o.min_disparity = 0.0;
  o.max_disparity = 50.0;
  EXPECT_EQ(ApplyGeometricCheck(a, b, m, o).size(), 10u);
  o.geometric_check = GeometricCheck::kHomography;
  bool failed = true;
  const std::vector<Match> h = ApplyGeometricCheck(a, b, m, o, &failed);
  EXPECT_FALSE(failed);
  EXPECT_EQ(h.size(), 10u);
  // Too few matches for a homography: a status, not a crash.
  const std::vector<Match> few(m.begin(), m.begin() + 3);
  EXPECT_TRUE(ApplyGeometricCheck(a, b, few, o, &failed).empty());
  EXPECT_TRUE(failed);
}

TEST(MatcherTest, KittiStereoAndConsecutiveFrames) {
  DALA_SKIP_WITHOUT_SHARED_DATA("kitti06_0000-0050");
  const std::string dir = ::dala::testing::SharedDataDir() + "/kitti06_0000-0050/";
  const cv::Mat l0 = cv::imread(dir + "image_0/000000.png", cv::IMREAD_GRAYSCALE);
  const cv::Mat r0 = cv::imread(dir + "image_1/000000.png", cv::IMREAD_GRAYSCALE);
  const cv::Mat l1 = cv::imread(dir + "image_0/000001.png", cv::IMREAD_GRAYSCALE);
  ASSERT_FALSE(l0.empty() || r0.empty() || l1.empty());
  const DetectedImage dl0 = DetectHarris(l0, HarrisOptions());
  const DetectedImage dr0 = DetectHarris(r0, HarrisOptions());
  const DetectedImage dl1 = DetectHarris(l1, HarrisOptions());
  // Rectified stereo: the same row, disparity up to 120 px (fx 707, baseline 0.54 m: > 3 m).
  const MatchPrior stereo = MatchPrior::RectifiedStereo(1.5, 0.0, 120.0);
  const std::vector<Match> s = MatchPoints(dl0, dr0, MatcherOptions::ForStereo(), &stereo);
  EXPECT_GT(s.size(), 500u);
  // Consecutive frames with a fundamental-matrix check: almost all survive it with 2 px (94 % at
  // writing; 81 % with 1 px: points of coarse levels are localised to about their scale).
  MatcherOptions track = MatcherOptions::ForTracking();
  track.geometric_check = GeometricCheck::kNone;
  const std::vector<Match> t = MatchPoints(dl0, dl1, track);
  track.geometric_check = GeometricCheck::kFundamental;
  track.ransac_threshold_px = 2.0;
  const std::vector<Match> tf = MatchPoints(dl0, dl1, track);
  EXPECT_GT(t.size(), 500u);
  EXPECT_GT(static_cast<double>(tf.size()) / t.size(), 0.9);
}

}  // namespace
}  // namespace dala
