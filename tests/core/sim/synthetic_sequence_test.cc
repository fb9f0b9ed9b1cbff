#include "core/sim/synthetic_sequence.h"

#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/imgproc.hpp>

#include "core/error.h"
#include "core/sim/world.h"
#include "tests/test_util.h"

namespace dala::sim {
namespace {

SimOptions SmallOptions(const std::string& preset) {
  SimOptions o;
  o.preset = preset;
  o.texture_size = 256;  // Fast to build; the geometry is the same.
  return o;
}

bool Identical(const cv::Mat& a, const cv::Mat& b) {
  return a.size() == b.size() && a.type() == b.type() && cv::norm(a, b, cv::NORM_INF) == 0;
}

TEST(SyntheticSequenceTest, SameSeedGivesIdenticalImagesDifferentSeedDifferent) {
  SimOptions o = SmallOptions("rover_loop");
  o.brightness_change = 0.2;
  const SyntheticSequence a(o), b(o);
  const Frame fa = a.Render(5), fb = b.Render(5);
  ASSERT_TRUE(fa.is_stereo());
  EXPECT_TRUE(Identical(fa.left, fb.left));
  EXPECT_TRUE(Identical(fa.right, fb.right));
  // Render order does not matter (noise is seeded per frame and camera).
  a.Render(9);
  EXPECT_TRUE(Identical(a.Render(5).left, fa.left));

  o.seed = 2;
  const SyntheticSequence c(o);
  const Frame fc = c.Render(5);
  EXPECT_GT(cv::norm(fa.left, fc.left, cv::NORM_L1) / fa.left.total(), 5.0);
  // The path is the preset's, independent of the seed: same ground truth.
  EXPECT_POSE_NEAR(*fa.T_w_c0_gt, *fc.T_w_c0_gt, 1e-12);
}

TEST(SyntheticSequenceTest, FrameCarriesTimeAndGroundTruth) {
  SimOptions o = SmallOptions("fast");
  o.fps = 20;
  o.frames = 30;
  o.stereo = false;
  const SyntheticSequence seq(o);
  ASSERT_EQ(seq.size(), 30u);
  const Frame f = seq.Render(7);
  EXPECT_EQ(f.id.value, 7);
  EXPECT_EQ(f.t_ns, 350000000);
  EXPECT_FALSE(f.is_stereo());
  EXPECT_EQ(f.left.type(), CV_8UC1);
  EXPECT_EQ(f.left.cols, 752);
  EXPECT_EQ(f.left.rows, 480);
  ASSERT_TRUE(f.T_w_c0_gt.has_value());
  EXPECT_POSE_NEAR(*f.T_w_c0_gt, seq.T_w_c0(7), 1e-12);
  EXPECT_POSE_NEAR(seq.ground_truth().poses[7].T_w_c, seq.T_w_c0(7), 1e-12);
  EXPECT_EQ(seq.ground_truth().poses[7].t_ns, f.t_ns);
}

TEST(SyntheticSequenceTest, DefaultFramesFollowPresetDuration) {
  for (const std::string& name : PresetNames()) {
    SimOptions o = SmallOptions(name);
    o.texture_size = 64;
    const SyntheticSequence seq(o);
    EXPECT_EQ(seq.size(), static_cast<size_t>(std::lround(FindPreset(name)->duration_s * 10)))
        << name;
  }
}

TEST(SyntheticSequenceTest, InvalidOptionsAreRejected) {
  std::string why;
  SimOptions o;
  EXPECT_TRUE(o.IsValid(&why)) << why;
  o.preset = "moon_landing";
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("rover_loop"), std::string::npos) << why;  // Lists the valid names.
  EXPECT_THROW(SyntheticSequence{o}, Error);
  o = SimOptions();
  o.fps = 0;
  EXPECT_FALSE(o.IsValid(&why));
  o = SimOptions();
  o.baseline = -0.1;
  EXPECT_FALSE(o.IsValid(&why));
  o.stereo = false;
  EXPECT_TRUE(o.IsValid(&why));  // The baseline does not matter for mono.
  o = SimOptions();
  o.texture_size = 300;
  EXPECT_FALSE(o.IsValid(&why));
  for (const double scale : {0.0, -1.0, 17.0}) {
    o = SimOptions();
    o.texel_density_scale = scale;
    EXPECT_FALSE(o.IsValid(&why)) << scale;
  }
  o = SimOptions();
  o.noise_sigma = -1;
  EXPECT_FALSE(o.IsValid(&why));
}

// The rendered depth map agrees with the geometry: every pixel's back-projection (gt pose,
// intrinsics, depth) lies on a scene patch, and patch centres project where the depth map says.
TEST(SyntheticSequenceTest, DepthMapAgreesWithSceneGeometryAndGroundTruthPose) {
  for (const std::string preset : {"rover_loop", "flight"}) {
    const SyntheticSequence seq(SmallOptions(preset));
    const size_t i = seq.size() / 3;
    const Pose T_w_c = seq.T_w_c0(i);
    cv::Mat depth;
    seq.RenderView(T_w_c, &depth);
    ASSERT_EQ(depth.type(), CV_32FC1);
    const Eigen::Matrix3d K = seq.K();
    const std::vector<Surface>& surfaces = seq.scene().surfaces;
    // 1) Back-projection of a grid of pixels lands on a patch.
    int checked = 0;
    for (int v = 5; v < depth.rows; v += 47) {
      for (int u = 5; u < depth.cols; u += 53) {
        const float z = depth.at<float>(v, u);
        if (z <= 0) continue;
        const Eigen::Vector3d p_c = z * K.inverse() * Eigen::Vector3d(u, v, 1);
        const Eigen::Vector3d p_w = T_w_c * p_c;
        bool on_patch = false;
        for (const Surface& s : surfaces) {
          const Eigen::Vector3d n = s.a_w.cross(s.b_w).normalized();
          if (std::abs(n.dot(p_w - s.o_w)) > 1e-4 * z) continue;
          // Patch coordinates by least squares on the two edges.
          Eigen::Matrix<double, 3, 2> A;
          A << s.a_w, s.b_w;
          const Eigen::Vector2d st = A.colPivHouseholderQr().solve(p_w - s.o_w);
          const double eps = 1e-4;
          if (st.x() < -eps || st.y() < -eps) continue;
          if (s.triangle ? st.sum() > 1 + eps : (st.x() > 1 + eps || st.y() > 1 + eps)) continue;
          on_patch = true;
          break;
        }
        EXPECT_TRUE(on_patch) << preset << " pixel " << u << "," << v << " z " << z;
        ++checked;
      }
    }
    EXPECT_GT(checked, 40) << preset;
    // 2) Points on a 4x4 grid of every patch in view: the depth map at their projection
    // matches their z when they are visible, and is nearer when they are occluded (never
    // farther).
    int visible = 0;
    const Pose T_c_w = T_w_c.inverse();
    for (const Surface& s : surfaces) {
      for (int gi = 0; gi < 4; ++gi) {
        for (int gj = 0; gj < 4; ++gj) {
          const double ps = (gi + 0.5) / 4, pt = (gj + 0.5) / 4;
          if (s.triangle && ps + pt > 1) continue;
          const Eigen::Vector3d x_w = s.o_w + ps * s.a_w + pt * s.b_w;
          const Eigen::Vector3d p_c = T_c_w * x_w;
          // Near patches seen not too obliquely: there half a pixel of rounding moves z little.
          if (p_c.z() < 0.5 || p_c.z() > 60) continue;
          const Eigen::Vector3d n_c = T_c_w.linear() * s.a_w.cross(s.b_w).normalized();
          if (std::abs(n_c.dot(p_c.normalized())) < 0.3) continue;
          const Eigen::Vector3d uv = K * p_c / p_c.z();
          const int u = static_cast<int>(std::lround(uv.x()));
          const int v = static_cast<int>(std::lround(uv.y()));
          if (u < 2 || v < 2 || u >= depth.cols - 2 || v >= depth.rows - 2) continue;
          const float z = depth.at<float>(v, u);
          ASSERT_GT(z, 0.f) << "a scene point in view projects to sky";
          EXPECT_LT(z, p_c.z() * 1.05 + 0.05) << preset;
          if (std::abs(z - p_c.z()) < 0.02 * p_c.z()) ++visible;
        }
      }
    }
    EXPECT_GT(visible, 50) << preset;
  }
}

// The pair is rectified: a left pixel at depth z appears in the right image at u - fx b / z on
// the same row, with the same depth and the same intensity.
TEST(SyntheticSequenceTest, StereoPairIsRectified) {
  SimOptions o = SmallOptions("rover_loop");
  const SyntheticSequence seq(o);
  const Pose T_w_c0 = seq.T_w_c0(40);
  cv::Mat depth0, depth1;
  const cv::Mat left = seq.RenderView(T_w_c0, &depth0);
  const cv::Mat right = seq.RenderView(T_w_c0 * seq.T_c0_c1(), &depth1);
  // The clean stereo frame equals RenderView of the two poses up to noise.
  o.noise_sigma = 0;
  const Frame f = SyntheticSequence(o).Render(40);
  EXPECT_TRUE(Identical(f.left, left));
  EXPECT_TRUE(Identical(f.right, right));

  const double fx = seq.camera().fx, b = o.baseline;
  int n = 0, depth_ok = 0;
  std::vector<double> photometric;
  for (int v = 10; v < depth0.rows - 10; v += 7) {
    for (int u = 10; u < depth0.cols - 10; u += 7) {
      const float z = depth0.at<float>(v, u);
      if (z <= 0) continue;
      // Skip depth discontinuities (occlusions differ between the views).
      const float z_l = depth0.at<float>(v, u - 2), z_r = depth0.at<float>(v, u + 2);
      if (std::abs(z_l - z) > 0.05 * z || std::abs(z_r - z) > 0.05 * z) continue;
      const double ur = u - fx * b / z;
      const int iu = static_cast<int>(std::lround(ur));
      if (iu < 2 || iu >= depth1.cols - 2) continue;
      ++n;
      if (std::abs(depth1.at<float>(v, iu) - z) < 0.02 * z) ++depth_ok;
      cv::Mat patch;
      cv::getRectSubPix(right, cv::Size(1, 1), cv::Point2f(static_cast<float>(ur), v), patch,
                        CV_32F);
      photometric.push_back(std::abs(patch.at<float>(0, 0) - left.at<uchar>(v, u)));
    }
  }
  ASSERT_GT(n, 1000);
  EXPECT_GT(depth_ok, 0.97 * n);
  std::nth_element(photometric.begin(), photometric.begin() + photometric.size() / 2,
                   photometric.end());
  EXPECT_LT(photometric[photometric.size() / 2], 3.0);
}

TEST(SyntheticSequenceTest, RoverLoopClosesAndHasRealisticLength) {
  const SyntheticSequence seq(SmallOptions("rover_loop"));
  const Pose& first = seq.ground_truth().poses.front().T_w_c;
  const Pose& last = seq.ground_truth().poses.back().T_w_c;
  EXPECT_LT((first.translation() - last.translation()).norm(), 3.0);
  EXPECT_LT(LogSO3(first.linear().transpose() * last.linear()).norm(), 0.2);
  EXPECT_GT(seq.PathLength(), 100.0);
  EXPECT_LT(seq.PathLength(), 300.0);
  // Camera ~1.5 m above the flat ground, looking roughly horizontally.
  for (const auto& p : seq.ground_truth().poses) {
    EXPECT_NEAR(p.T_w_c.translation().z(), 1.5, 0.1);
    const Eigen::Vector3d forward_w = p.T_w_c.linear().col(2);
    EXPECT_LT(std::abs(forward_w.z()), 0.15);
  }
  // The loop is traversed once: the half-way point is far from the start.
  const Pose& mid = seq.ground_truth().poses[seq.size() / 2].T_w_c;
  EXPECT_GT((mid.translation() - first.translation()).norm(), 40.0);
}

TEST(SyntheticSequenceTest, PathsAreSmoothAndRotationIsInPlace) {
  for (const std::string& name : PresetNames()) {
    SimOptions o = SmallOptions(name);
    o.texture_size = 64;
    const SyntheticSequence seq(o);
    double max_step = 0, max_angle = 0;
    for (size_t i = 1; i < seq.size(); ++i) {
      const Pose d = seq.T_w_c0(i - 1).inverse() * seq.T_w_c0(i);
      max_step = std::max(max_step, d.translation().norm());
      max_angle = std::max(max_angle, LogSO3(d.linear()).norm());
    }
    EXPECT_LT(max_step, 1.2) << name;    // < 12 m/s at 10 Hz.
    EXPECT_LT(max_angle, 0.25) << name;  // < 15 deg per frame even for `fast`.
    if (name == "rotation") {
      EXPECT_LT(seq.PathLength(), 1e-9);
      EXPECT_GT(max_angle, 0.02);
    } else {
      EXPECT_GT(seq.PathLength(), 80.0) << name;
    }
  }
}

double Ncc(const cv::Mat& a, const cv::Mat& b) {
  cv::Mat r;
  cv::matchTemplate(a, b, r, cv::TM_CCOEFF_NORMED);
  return r.at<float>(0, 0);
}

// false_loop: the street at x and x + 100 m looks alike (a false loop closure) although the
// camera is 100 m away, while the street 50 m further on does not.
TEST(SyntheticSequenceTest, FalseLoopRevisitsLookAlikeButDistinctPlaces) {
  SimOptions o = SmallOptions("false_loop");
  o.stereo = false;
  const SyntheticSequence seq(o);
  const size_t at_60m = 300, at_160m = 800, at_110m = 550;  // 2 m/s at 10 Hz.
  EXPECT_NEAR(seq.T_w_c0(at_60m).translation().x(), 60.0, 1e-9);
  EXPECT_GT((seq.T_w_c0(at_160m).translation() - seq.T_w_c0(at_60m).translation()).norm(), 99.0);
  // Never within 20 m of an earlier pose after moving 40 m away: no true loop.
  for (size_t i = 0; i < seq.size(); i += 10) {
    for (size_t j = i + 200; j < seq.size(); j += 10) {
      EXPECT_GT((seq.T_w_c0(i).translation() - seq.T_w_c0(j).translation()).norm(), 20.0);
    }
  }
  cv::Mat a = seq.RenderView(seq.T_w_c0(at_60m)), b = seq.RenderView(seq.T_w_c0(at_160m));
  cv::Mat c = seq.RenderView(seq.T_w_c0(at_110m));
  // Compare the lower two thirds (near street, walls); the far skyline differs.
  const cv::Rect roi(0, 160, 752, 320);
  EXPECT_GT(Ncc(a(roi), b(roi)), 0.8);
  EXPECT_LT(Ncc(a(roi), c(roi)), 0.3);
}

TEST(SyntheticSequenceTest, MotionBlurAndBrightnessChangeTheImages) {
  SimOptions o = SmallOptions("fast");
  o.stereo = false;
  o.noise_sigma = 0;
  const cv::Mat sharp = SyntheticSequence(o).Render(20).left;
  o.motion_blur = true;
  const cv::Mat blurred = SyntheticSequence(o).Render(20).left;
  cv::Mat gs, gb;
  cv::Laplacian(sharp, gs, CV_32F);
  cv::Laplacian(blurred, gb, CV_32F);
  EXPECT_LT(cv::norm(gb, cv::NORM_L2), 0.8 * cv::norm(gs, cv::NORM_L2));
  o.motion_blur = false;
  o.brightness_change = 0.3;
  const SyntheticSequence bright(o);
  double lo = 1e9, hi = 0;
  for (size_t i = 0; i < 64; i += 8) {
    const double m = cv::mean(bright.Render(i).left)[0];
    lo = std::min(lo, m), hi = std::max(hi, m);
  }
  EXPECT_GT(hi - lo, 20.0);
}

// More texels per metre: every surface's texel axes grow by the scale; the geometry, the
// textures and their placement do not change.
TEST(SyntheticSequenceTest, TexelDensityScaleMultipliesEverySurfacesTexelsPerMetre) {
  for (const std::string preset : {"rover_loop", "flight", "false_loop"}) {
    SCOPED_TRACE(preset);
    const World coarse = BuildWorld(preset, 3, 64);
    const World fine = BuildWorld(preset, 3, 64, 2.5);
    ASSERT_EQ(coarse.scene.surfaces.size(), fine.scene.surfaces.size());
    for (size_t i = 0; i < coarse.scene.surfaces.size(); ++i) {
      const Surface& c = coarse.scene.surfaces[i];
      const Surface& f = fine.scene.surfaces[i];
      ASSERT_TRUE(c.o_w == f.o_w && c.a_w == f.a_w && c.b_w == f.b_w && c.texture == f.texture);
      ASSERT_NEAR(f.uv_a.norm(), 2.5 * c.uv_a.norm(), 1e-9 * f.uv_a.norm());
      ASSERT_NEAR(f.uv_b.norm(), 2.5 * c.uv_b.norm(), 1e-9 * f.uv_b.norm());
    }
  }
}

TEST(NoisyOdometryTest, ZeroNoiseIsGroundTruthAndNoiseDriftsDeterministically) {
  SimOptions o = SmallOptions("rover_loop");
  o.texture_size = 64;
  const SyntheticSequence seq(o);
  const Trajectory& gt = seq.ground_truth();
  const Trajectory exact = NoisyOdometry(gt, 3, 0, 0, 0);
  ASSERT_EQ(exact.size(), gt.size());
  EXPECT_POSE_NEAR(exact.poses.back().T_w_c, gt.poses.back().T_w_c, 1e-6);
  const Trajectory noisy = NoisyOdometry(gt, 3, 0.002, 0.005, 0.02);
  const Trajectory again = NoisyOdometry(gt, 3, 0.002, 0.005, 0.02);
  EXPECT_POSE_NEAR(noisy.poses.back().T_w_c, again.poses.back().T_w_c, 1e-15);
  const double drift =
      (noisy.poses.back().T_w_c.translation() - gt.poses.back().T_w_c.translation()).norm();
  EXPECT_GT(drift, 0.1);
  EXPECT_LT(drift, 60.0);
  // One step's error is of the size of the noise.
  const Pose step_gt = gt.poses[0].T_w_c.inverse() * gt.poses[1].T_w_c;
  const Pose step = noisy.poses[0].T_w_c.inverse() * noisy.poses[1].T_w_c;
  EXPECT_LT((step.translation() - step_gt.translation()).norm(), 0.1);
}

}  // namespace
}  // namespace dala::sim
