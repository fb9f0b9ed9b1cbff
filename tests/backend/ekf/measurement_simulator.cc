#include "tests/backend/ekf/measurement_simulator.h"

#include <cmath>
#include <optional>
#include <random>
#include <utility>

namespace dala::testing {

StereoRig SimRig() {
  StereoRig rig;
  rig.left.width = 640;
  rig.left.height = 480;
  rig.left.fx = rig.left.fy = 400.0;
  rig.left.cx = 319.5;
  rig.left.cy = 239.5;
  rig.baseline = 0.5;
  return rig;
}

namespace {

struct StereoPoint {
  Eigen::Vector3d p_c;
  Eigen::Matrix3d cov;
};

// Weighted 3D-3D alignment a_k = T b_k (T = T_prev_cur), Gauss-Newton from T0 with the right
// perturbation T Exp([phi; rho]): d(T Exp(d) b)/d d = [-R [b]x, R]; weight (A + R B R^T)^-1.
MotionEstimate AlignStereoPoints(const std::vector<std::pair<StereoPoint, StereoPoint>>& pairs,
                                 const Pose& T0) {
  MotionEstimate motion;
  Pose T = T0;
  Matrix6d JtWJ = Matrix6d::Identity();
  for (int iteration = 0; iteration < 6; ++iteration) {
    JtWJ.setZero();
    Vector6d JtWr = Vector6d::Zero();
    const Eigen::Matrix3d R = T.linear();
    for (const auto& [a, b] : pairs) {
      const Eigen::Matrix3d W = (a.cov + R * b.cov * R.transpose()).inverse();
      Eigen::Matrix<double, 3, 6> J;
      J << -R * Skew(b.p_c), R;
      const Eigen::Vector3d r = a.p_c - T * b.p_c;
      JtWJ += J.transpose() * W * J;
      JtWr += J.transpose() * W * r;
    }
    T = Orthonormalized(T * ExpSE3(JtWJ.ldlt().solve(JtWr)));
  }
  motion.T_prev_cur = T;
  motion.cov = JtWJ.inverse();
  motion.inliers = motion.correspondences = static_cast<int>(pairs.size());
  return motion;
}

Pose PathPose(const SimOptions& o, int i) {
  const double t = static_cast<double>(i);
  switch (o.path) {
    case SimPath::kLateral:
      return MakePose(Eigen::Matrix3d::Identity(), Eigen::Vector3d(o.speed * t, 0, 0));
    case SimPath::kCircle: {
      // Centre at (radius, 0, 0): the camera starts at the origin looking along +z and turns
      // right (yaw about +y, which points down).
      const double a = 2 * M_PI * o.turns * t / o.frames;
      const Eigen::Vector3d p(o.radius * (1 - std::cos(a)), 0, o.radius * std::sin(a));
      return MakePose(ExpSO3(Eigen::Vector3d(0, a, 0)), p);
    }
    case SimPath::kCurve:
    default: {
      // Heading integrated numerically so the camera moves along its optical axis.
      Eigen::Vector3d p = Eigen::Vector3d::Zero();
      auto yaw = [](double s) { return 0.6 * std::sin(2 * M_PI * s / 120.0); };
      for (int k = 0; k < i; ++k) {
        const double y = yaw(k + 0.5);
        p += o.speed * Eigen::Vector3d(std::sin(y), 0, std::cos(y));
      }
      const Eigen::Vector3d phi(0.03 * std::sin(t / 17.0), yaw(t), 0.03 * std::sin(t / 11.0));
      const Pose T = MakePose(ExpSO3(phi), p);
      return T;
    }
  }
}

}  // namespace

SimStream Simulate(const SimOptions& o) {
  SimStream s;
  s.rig = SimRig();
  std::mt19937 rng(o.seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);

  const Pose T0_inv = PathPose(o, 0).inverse();
  for (int i = 0; i < o.frames; ++i) {
    s.T_w_c_gt.push_back(Orthonormalized(T0_inv * PathPose(o, i)));
    s.gt.Add(static_cast<int64_t>(i) * 100000000, s.T_w_c_gt.back());
  }
  const PinholeCamera& cam = s.rig.left;
  if (!o.points_w.empty()) {
    s.points_w = o.points_w;
  } else {
    for (int j = 0; j < o.num_points; ++j) {
      const int k = std::min(o.frames - 1, static_cast<int>(uniform(rng) * o.frames));
      const Eigen::Vector2d uv(uniform(rng) * (cam.width - 1), uniform(rng) * (cam.height - 1));
      const double z = o.point_min_depth + uniform(rng) * (o.point_max_depth - o.point_min_depth);
      s.points_w.push_back(s.T_w_c_gt[k] * (cam.Unproject(uv) * z));
    }
  }

  const int n = static_cast<int>(s.points_w.size());
  std::vector<int64_t> id(n);
  std::vector<int> last_seen(n, -1000), track(n, 0);
  std::vector<bool> seen_early(n, false);  // Seen in the first loop_old_frames frames.
  for (int j = 0; j < n; ++j) id[j] = j;
  int64_t next_id = n;
  Pose T_dr = Pose::Identity();
  std::vector<std::optional<StereoPoint>> previous(n), current(n);
  for (int i = 0; i < o.frames; ++i) {
    FrameMeasurement m;
    m.frame = FrameId(i);
    m.t_ns = s.gt.poses[i].t_ns;
    m.stereo = o.stereo;
    if (i == 0) {
      m.status = TrackingStatus::kInitializing;
    } else if (o.lost_frames.count(i) > 0) {
      m.status = TrackingStatus::kLost;
    } else {
      m.status = TrackingStatus::kTracking;
      const Pose M_true = s.T_w_c_gt[i - 1].inverse() * s.T_w_c_gt[i];
      Vector6d eta, sigma;
      sigma << o.motion_sigma_rot, o.motion_sigma_rot, o.motion_sigma_rot, o.motion_sigma_trans,
          o.motion_sigma_trans, o.motion_sigma_trans;
      for (int k = 0; k < 6; ++k) eta[k] = sigma[k] * normal(rng);
      MotionEstimate motion;
      motion.T_prev_cur = Orthonormalized(M_true * ExpSE3(-eta));
      motion.cov = sigma.cwiseAbs2().asDiagonal();
      motion.scale_known = true;
      m.motion = motion;
      if (o.fill_odometry) m.odometry = motion;
    }
    const Pose T_c_w = s.T_w_c_gt[i].inverse();
    for (int j = 0; j < n; ++j) {
      const Eigen::Vector3d p_c = T_c_w * s.points_w[j];
      if (p_c.z() < 0.3 || p_c.z() > 150.0) continue;
      Eigen::Vector2d uv;
      if (!cam.Project(p_c, &uv) || !cam.InImage(uv, 2.0)) continue;
      FeatureObservation obs;
      obs.uv = uv + o.sigma_px * Eigen::Vector2d(normal(rng), normal(rng));
      obs.sigma_px = o.sigma_px;
      if (o.stereo) {
        const double u_right =
            uv.x() - cam.fx * s.rig.baseline / p_c.z() + o.sigma_px * normal(rng);
        const Eigen::Vector3d uvd(obs.uv.x(), obs.uv.y(), obs.uv.x() - u_right);
        if (!(uvd.z() > 0.5)) continue;
        obs.u_right = u_right;
        // First-order covariance with the u-d correlation (d = u - u_right shares u's noise).
        Eigen::Matrix3d J;
        s.rig.Triangulate(uvd, &obs.p_c0, &J);
        Eigen::Matrix3d R;
        R << 1, 0, 1, 0, 1, 0, 1, 0, 2;
        obs.cov_p_c0 = J * (o.sigma_px * o.sigma_px * R) * J.transpose();
        current[j] = StereoPoint{obs.p_c0, obs.cov_p_c0};
      }
      if (last_seen[j] < i - 1) {
        track[j] = 0;
        if (!o.persistent_ids && last_seen[j] >= 0) id[j] = next_id++;
      }
      if (i < o.loop_old_frames && id[j] == j) seen_early[j] = true;
      if (i == o.loop_frame && seen_early[j] && id[j] != j) {
        if (!m.loop.has_value()) {
          m.loop = LoopDetection();
          m.is_keyframe = true;
          m.loop->old_frame = FrameId(0);
          m.loop->T_old_cur = s.T_w_c_gt[i];  // T_w_c0 with the first frame as the world.
        }
        m.loop->relabelled.emplace_back(LandmarkId(id[j]), LandmarkId(j));
        ++m.loop->inliers;
        id[j] = j;
      }
      last_seen[j] = i;
      obs.track_length = ++track[j];
      obs.landmark = LandmarkId(id[j]);
      m.observations.push_back(obs);
    }
    if (m.motion.has_value() && o.motion_from_stereo_points) {
      std::vector<std::pair<StereoPoint, StereoPoint>> pairs;
      for (int j = 0; j < n; ++j) {
        if (previous[j].has_value() && current[j].has_value()) {
          pairs.emplace_back(*previous[j], *current[j]);
        }
      }
      if (pairs.size() >= 3) {
        const Pose M_true = s.T_w_c_gt[i - 1].inverse() * s.T_w_c_gt[i];
        m.motion = AlignStereoPoints(pairs, M_true);
        if (o.fill_odometry) m.odometry = m.motion;
      }
    }
    if (m.motion.has_value()) T_dr = Orthonormalized(T_dr * m.motion->T_prev_cur);
    s.dead_reckoning.Add(m.t_ns, T_dr);
    previous.swap(current);
    for (auto& p : current) p.reset();
    s.frames.push_back(std::move(m));
  }
  return s;
}

}  // namespace dala::testing
