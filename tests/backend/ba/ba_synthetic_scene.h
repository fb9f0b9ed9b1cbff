#ifndef DALA_TESTS_BACKEND_BA_BA_SYNTHETIC_SCENE_H_
#define DALA_TESTS_BACKEND_BA_BA_SYNTHETIC_SCENE_H_

// Geometric synthetic data for the BA tests and benchmark (no images): a camera trajectory along
// a gentle curve, random world points in a corridor around it, and noisy stereo or mono
// projections of the visible points. Deterministic for a given seed.

#include <Eigen/Geometry>
#include <cmath>
#include <random>
#include <vector>

#include "backend/ba/ba_types.h"
#include "core/geometry.h"
#include "tests/test_util.h"

namespace dala::testing {

struct BaSceneOptions {
  int num_keyframes = 30;
  int num_points = 500;
  double step_m = 0.6;          // distance between keyframes along the path.
  double turn_radius_m = 25.0;  // radius of the curve (yaw rate = step / radius).
  double pixel_noise = 0.5;     // sigma of u, v and u_r (px).
  bool stereo = true;
  double max_depth_m = 40.0;  // points farther from a camera are not observed by it.
  unsigned seed = 1;
};

struct BaScene {
  StereoIntrinsics K;
  int width = 640;
  int height = 480;
  std::vector<Pose> T_w_c_gt;
  std::vector<Eigen::Vector3d> p_w_gt;  // index = landmark id.
  // Keyframes with noisy observations; T_w_c is the ground truth (tests perturb it).
  std::vector<BaKeyframe> keyframes;
};

// Camera pose at arc length s: moving along world z, turning about world y (camera y is down),
// with a small pitch/roll wobble so that the motion is not planar.
inline Pose SceneCameraPose(double s, double radius) {
  const double yaw = s / radius;
  const Eigen::Vector3d c(radius * (1.0 - std::cos(yaw)), 0.3 * std::sin(s / 4.0),
                          radius * std::sin(yaw));
  const Eigen::Matrix3d R = (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitY()) *
                             Eigen::AngleAxisd(0.03 * std::sin(s / 3.0), Eigen::Vector3d::UnitX()) *
                             Eigen::AngleAxisd(0.02 * std::cos(s / 5.0), Eigen::Vector3d::UnitZ()))
                                .toRotationMatrix();
  return MakePose(R, c);
}

inline BaScene MakeBaScene(const BaSceneOptions& o) {
  BaScene scene;
  scene.K = {450.0, 450.0, 320.0, 240.0, o.stereo ? 0.5 : 0.0};
  std::mt19937 rng(o.seed);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  std::normal_distribution<double> noise(0.0, o.pixel_noise);
  for (int i = 0; i < o.num_keyframes; ++i) {
    scene.T_w_c_gt.push_back(SceneCameraPose(i * o.step_m, o.turn_radius_m));
  }
  const double length = (o.num_keyframes - 1) * o.step_m;
  // Points in a corridor: along the path up to 20 m ahead of the last keyframe, 2..10 m to the
  // side, -3..+1.5 m vertically (y down).
  while (static_cast<int>(scene.p_w_gt.size()) < o.num_points) {
    const double s = (length + 20.0) * uni(rng) + 2.0;
    const Pose T = SceneCameraPose(s, o.turn_radius_m);
    const double side = (uni(rng) < 0.5 ? -1.0 : 1.0) * (2.0 + 8.0 * uni(rng));
    const Eigen::Vector3d p_c(side, -3.0 + 4.5 * uni(rng), 0.0);
    const Eigen::Vector3d p_w = T * p_c;
    // Keep points seen by at least two keyframes.
    int seen = 0;
    for (const Pose& T_w_c : scene.T_w_c_gt) {
      const Eigen::Vector3d q = T_w_c.inverse() * p_w;
      const double u = scene.K.fx * q.x() / q.z() + scene.K.cx;
      const double v = scene.K.fy * q.y() / q.z() + scene.K.cy;
      if (q.z() > 1.0 && q.z() < o.max_depth_m && u > 5 && u < scene.width - 5 && v > 5 &&
          v < scene.height - 5) {
        ++seen;
      }
    }
    if (seen >= 2) scene.p_w_gt.push_back(p_w);
  }
  for (int i = 0; i < o.num_keyframes; ++i) {
    BaKeyframe kf;
    kf.id = KeyframeId(i);
    kf.t_ns = static_cast<int64_t>(i) * 100000000;
    kf.T_w_c = scene.T_w_c_gt[i];
    const Pose T_c_w = scene.T_w_c_gt[i].inverse();
    for (size_t j = 0; j < scene.p_w_gt.size(); ++j) {
      const Eigen::Vector3d q = T_c_w * scene.p_w_gt[j];
      const double u = scene.K.fx * q.x() / q.z() + scene.K.cx;
      const double v = scene.K.fy * q.y() / q.z() + scene.K.cy;
      if (!(q.z() > 1.0 && q.z() < o.max_depth_m && u > 5 && u < scene.width - 5 && v > 5 &&
            v < scene.height - 5)) {
        continue;
      }
      BaObservation obs;
      obs.landmark = LandmarkId(static_cast<int64_t>(j));
      obs.uv = Eigen::Vector2d(u + noise(rng), v + noise(rng));
      if (o.stereo) obs.u_right = u - scene.K.fx * scene.K.baseline / q.z() + noise(rng);
      obs.sigma_px = o.pixel_noise;
      kf.observations.push_back(obs);
    }
    scene.keyframes.push_back(kf);
  }
  return scene;
}

// T * Exp([rot_sigma * n; trans_sigma * n]) with n standard normal.
inline Pose PerturbPose(const Pose& T, std::mt19937& rng, double rot_sigma, double trans_sigma) {
  std::normal_distribution<double> n(0.0, 1.0);
  Vector6d xi;
  for (int i = 0; i < 6; ++i) xi[i] = n(rng) * (i < 3 ? rot_sigma : trans_sigma);
  return T * ExpSE3(xi);
}

// RMSE of positions after the best rigid (SE3, no scale) alignment (Umeyama), like evo's ATE.
inline double AlignedAte(const std::vector<Pose>& est, const std::vector<Pose>& gt,
                         bool with_scale = false) {
  Eigen::Matrix3Xd A(3, est.size()), B(3, gt.size());
  for (size_t i = 0; i < est.size(); ++i) {
    A.col(i) = est[i].translation();
    B.col(i) = gt[i].translation();
  }
  const Eigen::Matrix4d S = Eigen::umeyama(A, B, with_scale);
  const Eigen::Matrix3Xd aligned =
      (S.topLeftCorner<3, 3>() * A).colwise() + S.topRightCorner<3, 1>();
  return std::sqrt((aligned - B).colwise().squaredNorm().mean());
}

}  // namespace dala::testing

#endif  // DALA_TESTS_BACKEND_BA_BA_SYNTHETIC_SCENE_H_
