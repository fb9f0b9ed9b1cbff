#include "core/camera.h"

#include <gtest/gtest.h>

#include <random>

#include "tests/test_util.h"

namespace dala {
namespace {

PinholeCamera EurocLikeCamera() {
  // EuRoC V1 cam0 (a strong radial distortion, the hard case for the inverse).
  PinholeCamera cam;
  cam.width = 752;
  cam.height = 480;
  cam.fx = 458.654;
  cam.fy = 457.296;
  cam.cx = 367.215;
  cam.cy = 248.375;
  cam.distortion << -0.28340811, 0.07395907, 0.00019359, 1.76187114e-05, 0.0;
  return cam;
}

PinholeCamera KittiLikeCamera() {
  PinholeCamera cam;
  cam.width = 1226;
  cam.height = 370;
  cam.fx = cam.fy = 707.0912;
  cam.cx = 601.8873;
  cam.cy = 183.1104;
  return cam;
}

StereoRig KittiRig() { return StereoRig{KittiLikeCamera(), 0.537}; }

// Central differences of f: R^3 -> R^N.
template <int N, typename F>
Eigen::Matrix<double, N, 3> NumericJacobian(const F& f, const Eigen::Vector3d& x, double h) {
  Eigen::Matrix<double, N, 3> J;
  for (int i = 0; i < 3; ++i) {
    Eigen::Vector3d xp = x, xm = x;
    xp[i] += h;
    xm[i] -= h;
    J.col(i) = (f(xp) - f(xm)) / (2 * h);
  }
  return J;
}

Eigen::Vector3d RandomPointInFront(std::mt19937& rng, double z_min, double z_max) {
  std::uniform_real_distribution<double> z(z_min, z_max), xy(-0.6, 0.6);
  const double depth = z(rng);
  return Eigen::Vector3d(xy(rng) * depth, xy(rng) * 0.5 * depth, depth);
}

TEST(PinholeCamera, ProjectJacobianMatchesNumeric) {
  std::mt19937 rng(7);
  for (const PinholeCamera& cam : {KittiLikeCamera(), EurocLikeCamera()}) {
    PinholeCamera with_tangential = cam;
    with_tangential.distortion << -0.2, 0.05, 0.003, -0.002, 0.01;
    for (const PinholeCamera& c : {cam, with_tangential}) {
      for (int trial = 0; trial < 50; ++trial) {
        const Eigen::Vector3d p = RandomPointInFront(rng, 0.5, 30.0);
        Eigen::Vector2d uv;
        Eigen::Matrix<double, 2, 3> J;
        ASSERT_TRUE(c.Project(p, &uv, &J));
        const auto f = [&](const Eigen::Vector3d& q) {
          Eigen::Vector2d r;
          EXPECT_TRUE(c.Project(q, &r));
          return r;
        };
        const Eigen::Matrix<double, 2, 3> Jn = NumericJacobian<2>(f, p, 1e-6 * p.z());
        EXPECT_LT((J - Jn).cwiseAbs().maxCoeff(), 1e-5 * (1.0 + Jn.cwiseAbs().maxCoeff()))
            << "analytic\n"
            << J << "\nnumeric\n"
            << Jn;
      }
    }
  }
}

TEST(PinholeCamera, ProjectRejectsPointsBehind) {
  const PinholeCamera cam = KittiLikeCamera();
  Eigen::Vector2d uv(-1, -1);
  EXPECT_FALSE(cam.Project(Eigen::Vector3d(0.1, 0.2, 0.0), &uv));
  EXPECT_FALSE(cam.Project(Eigen::Vector3d(0.1, 0.2, -3.0), &uv));
  EXPECT_EQ(uv, Eigen::Vector2d(-1, -1));  // Untouched.
  ASSERT_TRUE(cam.Project(Eigen::Vector3d(0, 0, 2.0), &uv));
  EXPECT_NEAR(uv.x(), cam.cx, 1e-12);
  EXPECT_NEAR(uv.y(), cam.cy, 1e-12);
}

TEST(PinholeCamera, UnprojectInvertsProjectWithAndWithoutDistortion) {
  for (const PinholeCamera& cam : {KittiLikeCamera(), EurocLikeCamera()}) {
    // Every pixel of a grid over the whole image, corners included (largest distortion).
    for (double v = 0; v <= cam.height - 1; v += (cam.height - 1) / 8.0) {
      for (double u = 0; u <= cam.width - 1; u += (cam.width - 1) / 10.0) {
        const Eigen::Vector2d uv(u, v);
        const Eigen::Vector3d ray = cam.Unproject(uv);
        EXPECT_DOUBLE_EQ(ray.z(), 1.0);
        Eigen::Vector2d uv2;
        ASSERT_TRUE(cam.Project(ray * 3.7, &uv2));
        EXPECT_LT((uv2 - uv).norm(), 1e-6)
            << "pixel " << uv.transpose() << " distorted " << cam.HasDistortion();
      }
    }
  }
}

TEST(PinholeCamera, DistortionMovesCornersInward) {
  // Barrel distortion (k1 < 0): a corner ray lands closer to the centre than without distortion;
  // checks the sign convention against OpenCV's model.
  PinholeCamera distorted = EurocLikeCamera();
  PinholeCamera ideal = distorted;
  ideal.distortion.setZero();
  const Eigen::Vector3d p(0.6, 0.4, 1.0);
  Eigen::Vector2d uv_d, uv_i;
  ASSERT_TRUE(distorted.Project(p, &uv_d));
  ASSERT_TRUE(ideal.Project(p, &uv_i));
  const Eigen::Vector2d c(distorted.cx, distorted.cy);
  EXPECT_LT((uv_d - c).norm(), (uv_i - c).norm() - 20.0);
}

TEST(PinholeCamera, InImageAndValidity) {
  const PinholeCamera cam = KittiLikeCamera();
  EXPECT_TRUE(cam.InImage({0, 0}));
  EXPECT_TRUE(cam.InImage({1225, 369}));
  EXPECT_FALSE(cam.InImage({1225.5, 10}));
  EXPECT_FALSE(cam.InImage({-0.1, 10}));
  EXPECT_FALSE(cam.InImage({5, 5}, 10));
  EXPECT_TRUE(cam.InImage({10, 10}, 10));
  std::string why;
  EXPECT_TRUE(cam.IsValid(&why)) << why;
  PinholeCamera bad = cam;
  bad.fx = 0;
  EXPECT_FALSE(bad.IsValid(&why));
  EXPECT_NE(why.find("focal"), std::string::npos) << why;
  bad = cam;
  bad.width = 0;
  EXPECT_FALSE(bad.IsValid(&why));
  EXPECT_NE(why.find("size"), std::string::npos) << why;
  const Eigen::Matrix3d K = cam.K();
  EXPECT_EQ(K(0, 0), cam.fx);
  EXPECT_EQ(K(1, 2), cam.cy);
  EXPECT_EQ(K(2, 2), 1.0);
}

TEST(StereoRig, ProjectStereoJacobianAndDisparity) {
  const StereoRig rig = KittiRig();
  std::mt19937 rng(11);
  for (int trial = 0; trial < 100; ++trial) {
    const Eigen::Vector3d p = RandomPointInFront(rng, 1.0, 80.0);
    Eigen::Vector3d uvd;
    Eigen::Matrix3d J;
    ASSERT_TRUE(rig.ProjectStereo(p, &uvd, &J));
    // Disparity is u_left - u_right, with the right camera at +b along x.
    const Eigen::Vector3d p_c1 = rig.T_c0_c1().inverse() * p;
    Eigen::Vector2d uv_l, uv_r;
    ASSERT_TRUE(rig.left.Project(p, &uv_l));
    ASSERT_TRUE(rig.left.Project(p_c1, &uv_r));
    EXPECT_NEAR(uvd.z(), uv_l.x() - uv_r.x(), 1e-9);
    EXPECT_NEAR(uv_l.y(), uv_r.y(), 1e-9);
    EXPECT_NEAR(uvd.x(), uv_l.x(), 1e-9);
    const auto f = [&](const Eigen::Vector3d& q) {
      Eigen::Vector3d r;
      EXPECT_TRUE(rig.ProjectStereo(q, &r));
      return r;
    };
    const Eigen::Matrix3d Jn = NumericJacobian<3>(f, p, 1e-6 * p.z());
    EXPECT_LT((J - Jn).cwiseAbs().maxCoeff(), 1e-5 * (1.0 + Jn.cwiseAbs().maxCoeff()))
        << "analytic\n"
        << J << "\nnumeric\n"
        << Jn;
  }
  Eigen::Vector3d uvd;
  EXPECT_FALSE(rig.ProjectStereo(Eigen::Vector3d(1, 1, -1), &uvd));
}

TEST(StereoRig, TriangulateInvertsProjectStereoWithJacobian) {
  const StereoRig rig = KittiRig();
  std::mt19937 rng(13);
  for (int trial = 0; trial < 100; ++trial) {
    const Eigen::Vector3d p = RandomPointInFront(rng, 1.0, 80.0);
    Eigen::Vector3d uvd, p2;
    Eigen::Matrix3d J_proj, J_tri;
    ASSERT_TRUE(rig.ProjectStereo(p, &uvd, &J_proj));
    ASSERT_TRUE(rig.Triangulate(uvd, &p2, &J_tri));
    EXPECT_LT((p2 - p).norm(), 1e-9 * p.norm());
    const auto f = [&](const Eigen::Vector3d& q) {
      Eigen::Vector3d r;
      EXPECT_TRUE(rig.Triangulate(q, &r));
      return r;
    };
    const Eigen::Matrix3d Jn = NumericJacobian<3>(f, uvd, 1e-4);
    EXPECT_LT((J_tri - Jn).cwiseAbs().maxCoeff(), 1e-5 * (1.0 + Jn.cwiseAbs().maxCoeff()))
        << "analytic\n"
        << J_tri << "\nnumeric\n"
        << Jn;
    // Inverse functions have inverse Jacobians.
    EXPECT_LT((J_tri * J_proj - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff(), 1e-9);
  }
}

TEST(StereoRig, TriangulateRejectsNonPositiveDisparityAndMonoRigs) {
  StereoRig rig = KittiRig();
  Eigen::Vector3d p(7, 7, 7);
  EXPECT_FALSE(rig.Triangulate(Eigen::Vector3d(100, 100, 0.0), &p));
  EXPECT_FALSE(rig.Triangulate(Eigen::Vector3d(100, 100, -2.0), &p));
  EXPECT_EQ(p, Eigen::Vector3d(7, 7, 7));
  rig.baseline = 0;
  EXPECT_FALSE(rig.is_stereo());
  EXPECT_FALSE(rig.Triangulate(Eigen::Vector3d(100, 100, 5.0), &p));
}

TEST(StereoRig, TriangulationCovarianceGrowsWithSquaredDepth) {
  const StereoRig rig = KittiRig();
  const double sigma_px = 0.5, sigma_d = 0.7;
  double previous_ratio = -1;
  for (double z : {2.0, 5.0, 10.0, 20.0, 40.0}) {
    Eigen::Vector3d uvd;
    ASSERT_TRUE(rig.ProjectStereo(Eigen::Vector3d(0.0, 0.0, z), &uvd));
    const Eigen::Matrix3d cov = rig.TriangulationCovariance(uvd, sigma_px, sigma_d);
    EXPECT_LT((cov - cov.transpose()).norm(), 1e-12 * cov.norm());
    // On the optical axis: sigma_z = z^2 sigma_d / (fx b), sigma_x = z sigma_px / fx.
    const double expected_sigma_z = z * z * sigma_d / (rig.left.fx * rig.baseline);
    EXPECT_NEAR(std::sqrt(cov(2, 2)), expected_sigma_z, 1e-9 * expected_sigma_z);
    EXPECT_NEAR(std::sqrt(cov(0, 0)), z * sigma_px / rig.left.fx, 1e-12);
    const double ratio = std::sqrt(cov(2, 2)) / (z * z);
    if (previous_ratio > 0) {
      EXPECT_NEAR(ratio, previous_ratio, 1e-9 * ratio);
    }
    previous_ratio = ratio;
  }
  // Off axis the x-z correlation follows the ray direction: positive for x > 0.
  Eigen::Vector3d uvd;
  ASSERT_TRUE(rig.ProjectStereo(Eigen::Vector3d(3.0, 0.0, 10.0), &uvd));
  EXPECT_GT(rig.TriangulationCovariance(uvd, sigma_px, sigma_d)(0, 2), 0.0);
}

TEST(StereoRigDeathTest, CovarianceNeedsPositiveDisparity) {
  const StereoRig rig = KittiRig();
  EXPECT_DEATH(rig.TriangulationCovariance(Eigen::Vector3d(1, 1, 0), 1, 1), "positive disparity");
}

TEST(StereoRig, PoseAndValidity) {
  const StereoRig rig = KittiRig();
  EXPECT_POSE_NEAR(rig.T_c0_c1(),
                   MakePose(Eigen::Matrix3d::Identity(), Eigen::Vector3d(0.537, 0, 0)), 1e-15);
  std::string why;
  EXPECT_TRUE(rig.IsValid(&why)) << why;
  StereoRig bad = rig;
  bad.baseline = -0.5;
  EXPECT_FALSE(bad.IsValid(&why));
  EXPECT_NE(why.find("baseline"), std::string::npos);
  bad = rig;
  bad.left.distortion[0] = 0.1;
  EXPECT_FALSE(bad.IsValid(&why));
}

}  // namespace
}  // namespace dala
