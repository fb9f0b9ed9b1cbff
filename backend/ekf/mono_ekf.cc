#include "backend/ekf/mono_ekf.h"

#include <glog/logging.h>

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "backend/ekf/ekf_models.h"

namespace dala {

bool MonoEkfOptions::IsValid(std::string* why) const {
  std::ostringstream os;
  if (max_landmarks < 1) os << "max_landmarks must be >= 1; ";
  if (!(d_min > 0) || !(d_max > d_min)) os << "need 0 < d_min < d_max; ";
  if (!(alpha > 0) || !(k_sigma > 0) || !(alpha * k_sigma < 1)) {
    os << "need alpha > 0, k_sigma > 0 and alpha * k_sigma < 1 (beta finite); ";
  }
  if (!(prune_chi2 > 0) || !(gate_chi2 > 0)) os << "prune_chi2 and gate_chi2 must be > 0; ";
  if (!(sprt_false_alarm > 0 && sprt_false_alarm < 1) ||
      !(sprt_missed_detection > 0 && sprt_missed_detection < 1)) {
    os << "sprt_false_alarm and sprt_missed_detection must be in (0, 1); ";
  }
  if (!(min_image_motion_chi2 >= 0)) os << "min_image_motion_chi2 must be >= 0; ";
  if (pose_buffer_size < 2) os << "pose_buffer_size must be >= 2; ";
  if (max_candidates < 0 || max_directions < 0) os << "max_candidates/max_directions >= 0; ";
  if (infinity_after_frames < 1) os << "infinity_after_frames must be >= 1; ";
  if (grid_cols < 1 || grid_rows < 1) os << "grid_cols/grid_rows must be >= 1; ";
  if (target_per_zone < 0 || new_per_zone_per_frame < 0) os << "zone counts must be >= 0; ";
  if (max_gate_failures < 1 || evict_unseen_frames < 1) {
    os << "max_gate_failures and evict_unseen_frames must be >= 1; ";
  }
  if (!(lost_rotation_sigma >= 0) || !(lost_translation_sigma >= 0)) {
    os << "lost sigmas must be >= 0; ";
  }
  if (prediction != "auto" && prediction != "motion" && prediction != "constant_velocity") {
    os << "prediction must be auto, motion or constant_velocity (got '" << prediction << "'); ";
  }
  if (!(cv_angular_acceleration_sigma > 0) || !(cv_linear_acceleration_sigma > 0)) {
    os << "cv_angular_acceleration_sigma and cv_linear_acceleration_sigma must be > 0; ";
  }
  if (!(init_rotation_sigma > 0) || !(init_translation_sigma > 0)) {
    os << "init_rotation_sigma and init_translation_sigma must be > 0; ";
  }
  if (init_per_zone < 1) os << "init_per_zone must be >= 1; ";
  std::string init_why;
  if (!mono_init.IsValid(&init_why)) os << init_why << "; ";
  if (why != nullptr) *why = os.str();
  return os.str().empty();
}

std::vector<std::pair<double, double>> GaussianSumDepths(const MonoEkfOptions& o) {
  const double beta = (1 + o.alpha * o.k_sigma) / (1 - o.alpha * o.k_sigma);
  std::vector<std::pair<double, double>> depths;
  double s = o.d_min / (1 + o.alpha);
  while (true) {
    depths.emplace_back(s, o.alpha * s);
    if (s + o.alpha * s >= o.d_max) break;
    s *= beta;
  }
  return depths;
}

MonoEkfEstimator::MonoEkfEstimator(const PinholeCamera& camera, const MonoEkfOptions& options)
    : camera_(camera),
      options_(options),
      grid_(camera.width, camera.height, options.grid_cols, options.grid_rows),
      depths_(GaussianSumDepths(options)),
      state_(options.max_landmarks) {
  std::string why;
  CHECK(options.IsValid(&why)) << "MonoEkfOptions: " << why;
  CHECK(camera.IsValid(&why)) << "MonoEkfEstimator: " << why;
  CHECK(!camera.HasDistortion()) << "MonoEkfEstimator takes rectified (undistorted) pixels";
  if (options.prediction == "motion") {
    prediction_ = Prediction::kMotion;
  } else {
    // The filter starts from the pair as found: it has no window to track the checking frame
    // in, and weighs the next frames itself.
    MonoInitializerOptions init_options = options.mono_init;
    init_options.next_frame_min_inlier_ratio = 0.0;
    initializer_.emplace(camera, init_options);
    if (options.prediction == "constant_velocity") SwitchToConstantVelocity();
  }
}

std::string MonoEkfEstimator::prediction() const {
  switch (prediction_) {
    case Prediction::kMotion:
      return "motion";
    case Prediction::kConstantVelocity:
      return "constant_velocity";
    default:
      return "auto";
  }
}

void MonoEkfEstimator::SwitchToConstantVelocity() {
  prediction_ = Prediction::kConstantVelocity;
  state_ = EkfState(options_.max_landmarks, /*with_velocity=*/true);
  info_.clear();
  candidates_.clear();
  directions_.clear();
  rejected_.clear();
  pose_buffer_.clear();
  trajectory_ = Trajectory();
}

Matrix6d MonoEkfEstimator::VelocityNoise(double dt) const {
  const double sa = options_.cv_angular_acceleration_sigma;
  const double sl = options_.cv_linear_acceleration_sigma * initial_speed_;
  Vector6d var;
  var << sa * sa, sa * sa, sa * sa, sl * sl, sl * sl, sl * sl;
  return Matrix6d(var.asDiagonal()) * dt;
}

void MonoEkfEstimator::StartFromTwoView(const MonoInitialization& init) {
  const int n_steps = static_cast<int>(init.between.size()) + 1;
  double span = 1e-9 * static_cast<double>(init.current.t_ns - init.reference.t_ns);
  if (!(span > 0)) {
    LOG(WARNING) << "MonoEkf: timestamps do not increase; velocity per frame";
    span = n_steps;
  }
  // The mean velocity over the span, with the random walk over the span as its uncertainty.
  const Vector6d w0 = LogSE3(init.T_ref_cur) / span;
  initial_speed_ = w0.tail<3>().norm();
  Vector6d pose_var;
  const double sr = options_.init_rotation_sigma, st = options_.init_translation_sigma;
  pose_var << sr * sr, sr * sr, sr * sr, st * st, st * st, st * st;
  state_.Reset(init.T_ref_cur, pose_var.asDiagonal(), w0, VelocityNoise(span));
  last_t_ns_ = init.current.t_ns;
  last_dt_ = span / n_steps;
  trajectory_.Add(init.reference.t_ns, Pose::Identity());  // The world frame.

  // Landmarks: the two-view points with their triangulation covariance (poses fixed), the best
  // (smallest relative depth sigma) init_per_zone per zone of the current image.
  std::unordered_map<LandmarkId, const FeatureObservation*> in_ref, in_cur;
  for (const FeatureObservation& o : init.reference.observations) in_ref[o.landmark] = &o;
  for (const FeatureObservation& o : init.current.observations) in_cur[o.landmark] = &o;
  struct Point {
    int zone;
    double relative_sigma;
    LandmarkId id;
    Eigen::Vector3d p;
    Eigen::Matrix3d cov;
  };
  std::vector<Point> points;
  for (const auto& [id, p_ref] : init.p_ref) {
    const auto r = in_ref.find(id), c = in_cur.find(id);
    if (r == in_ref.end() || c == in_cur.end()) continue;
    Eigen::Vector2d uv;
    Eigen::Matrix<double, 2, 3> H_r, H_c;
    if (!PredictMonoObservation(camera_, Pose::Identity(), p_ref, &uv, nullptr, &H_r) ||
        !PredictMonoObservation(camera_, init.T_ref_cur, p_ref, &uv, nullptr, &H_c)) {
      continue;
    }
    const double s2_r = r->second->sigma_px * r->second->sigma_px;
    const double s2_c = c->second->sigma_px * c->second->sigma_px;
    const Eigen::Matrix3d info = H_r.transpose() * H_r / s2_r + H_c.transpose() * H_c / s2_c;
    const Eigen::LDLT<Eigen::Matrix3d> ldlt(info);
    if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().minCoeff() > 0)) continue;
    const Eigen::Matrix3d cov = ldlt.solve(Eigen::Matrix3d::Identity());
    const Eigen::Vector3d b = p_ref.normalized();
    const double relative_sigma = std::sqrt(b.dot(cov * b)) / p_ref.norm();
    if (!(relative_sigma < options_.alpha)) continue;
    points.push_back({grid_.Zone(c->second->uv), relative_sigma, id, p_ref, cov});
  }
  std::sort(points.begin(), points.end(), [](const Point& a, const Point& b) {
    if (a.zone != b.zone) return a.zone < b.zone;
    if (a.relative_sigma != b.relative_sigma) return a.relative_sigma < b.relative_sigma;
    return a.id < b.id;
  });
  std::vector<int> per_zone(grid_.size(), 0);
  for (const Point& pt : points) {
    if (state_.full()) break;
    if (per_zone[pt.zone] >= options_.init_per_zone) continue;
    ++per_zone[pt.zone];
    state_.AddLandmark(pt.id, pt.p, pt.cov, Eigen::Matrix<double, 3, 6>::Zero());
    info_[pt.id] = EkfLandmarkInfo{frame_index_, frame_index_, 2, 0};
  }
}

EstimatorOutput MonoEkfEstimator::AddBeforeInitialization(const FrameMeasurement& m) {
  EstimatorOutput out;
  const std::optional<MonoInitialization> init = initializer_->Add(m);
  if (!init) {
    out.initializing = true;
    out.note = "initialising: " + initializer_->reason();
    return out;
  }
  StartFromTwoView(*init);
  initializer_.reset();
  const std::vector<int> zone_count = UpdateState(m, /*apply_updates=*/false);
  ManageMap(m, PoseRecord{state_.T_w_c(), state_.pose_covariance()}, zone_count, &out);
  out.valid = true;
  std::ostringstream note;
  note.precision(3);
  note << "initialised from frame " << init->reference.frame << " (" << state_.num_landmarks()
       << " of " << init->p_ref.size() << " points, " << init->ModelName()
       << ", median parallax " << init->two_view.median_parallax_deg << " deg)";
  out.note = note.str();
  return out;
}

void MonoEkfEstimator::StartCandidate(const FeatureObservation& obs) {
  const PoseRecord& rec = pose_buffer_.at(frame_index_);
  const Eigen::Matrix3d R = rec.T_w_c.linear();
  Eigen::Matrix<double, 3, 2> d_b_d_uv;
  const Eigen::Vector3d b_c = PixelBearing(camera_, obs.uv, &d_b_d_uv);
  Candidate c;
  c.first_frame = c.last_used_frame = c.last_seen_frame = frame_index_;
  c.last_used_uv = obs.uv;
  c.d_w = R * b_c;
  const Eigen::Matrix3d cov_b_c = d_b_d_uv * (obs.sigma_px * obs.sigma_px) * d_b_d_uv.transpose();
  c.b_c = b_c;
  c.cov_b_c = cov_b_c;
  const Eigen::Matrix3d cov_ray = R * cov_b_c * R.transpose();
  // Direction covariance including the rotation uncertainty of the pose: d(R b)/dphi = -R [b]x.
  const Eigen::Matrix3d d_d_d_phi = -R * Skew(b_c);
  c.cov_d_w = cov_ray + d_d_d_phi * rec.cov.topLeftCorner<3, 3>() * d_d_d_phi.transpose();
  for (const auto& [s, sigma] : depths_) {
    Hypothesis h;
    h.s = s;
    h.sigma = sigma;
    h.p_k = s * b_c;
    h.cov_k = b_c * (sigma * sigma) * b_c.transpose() + s * s * cov_b_c;
    c.hypotheses.push_back(h);
  }
  c.observations.push_back({frame_index_, obs.uv, obs.sigma_px});
  candidates_.emplace(obs.landmark, std::move(c));
}

bool MonoEkfEstimator::UpdateCandidate(LandmarkId id, Candidate* c, const FeatureObservation& obs) {
  // Hypotheses are scored in the current camera through the relative pose T_c_k (estimate of the
  // filter, uncertainty from the motion inputs since frame k): the absolute pose uncertainties of
  // frames k and c are mostly common drift, which says nothing about the depth.
  const PoseRecord& first = pose_buffer_.at(c->first_frame);
  const Pose T_c_k = state_.T_w_c().inverse() * first.T_w_c;
  const Eigen::Matrix3d R_c_k = T_c_k.linear();
  const Matrix6d cov_ck = RelativeCovariance(c->first_frame);
  const double s2 = obs.sigma_px * obs.sigma_px;
  std::vector<Hypothesis> alive;
  const Hypothesis& farthest = c->hypotheses.back();
  bool farthest_kept = false;
  for (Hypothesis& h : c->hypotheses) {
    const Eigen::Vector3d p_c = T_c_k * h.p_k;
    Eigen::Vector2d uv;
    Eigen::Matrix<double, 2, 3> H_p;
    if (!camera_.Project(p_c, &uv, &H_p)) continue;
    Eigen::Matrix<double, 3, 6> J;
    J << -R_c_k * Skew(h.p_k), R_c_k;
    const Eigen::Matrix<double, 2, 3> H_k = H_p * R_c_k;
    const Eigen::Matrix2d R_obs =
        H_p * J * cov_ck * J.transpose() * H_p.transpose() + s2 * Eigen::Matrix2d::Identity();
    const Eigen::Matrix2d S = H_k * h.cov_k * H_k.transpose() + R_obs;
    const Eigen::Vector2d r = obs.uv - uv;
    const double m2 = r.dot(S.ldlt().solve(r));
    if (m2 > options_.prune_chi2) continue;
    // Predictive likelihood, then the hypothesis' own Kalman update (a Gaussian-sum filter: the
    // joint likelihood of all observations is the product of the predictive ones only when each
    // Gaussian is updated; a static Gaussian would be charged its log det S at every step).
    h.log_likelihood += -0.5 * m2 - std::log(2 * M_PI * std::sqrt(S.determinant()));
    const Eigen::Matrix<double, 3, 2> K = h.cov_k * H_k.transpose() * S.inverse();
    h.p_k += K * r;
    const Eigen::Matrix3d I_KH = Eigen::Matrix3d::Identity() - K * H_k;
    h.cov_k = I_KH * h.cov_k * I_KH.transpose() + K * R_obs * K.transpose();
    if (&h == &farthest && c->farthest_alive) farthest_kept = true;
    alive.push_back(h);
  }
  c->farthest_alive = farthest_kept;
  c->hypotheses = std::move(alive);
  c->observations.push_back({frame_index_, obs.uv, obs.sigma_px});
  c->last_used_frame = frame_index_;
  c->last_used_uv = obs.uv;

  // Updated hypotheses that have converged onto the best one carry the same information: merged
  // into it (dropped) when their means are within one sigma, (dp^T (C_i + C_best)^-1 dp < 1).
  if (c->hypotheses.size() > 1) {
    size_t best = 0;
    for (size_t i = 1; i < c->hypotheses.size(); ++i) {
      if (c->hypotheses[i].log_likelihood > c->hypotheses[best].log_likelihood) best = i;
    }
    const Hypothesis& hb = c->hypotheses[best];
    std::vector<Hypothesis> kept;
    for (size_t i = 0; i < c->hypotheses.size(); ++i) {
      const Hypothesis& h = c->hypotheses[i];
      const Eigen::Vector3d dp = h.p_k - hb.p_k;
      if (i != best && dp.dot((h.cov_k + hb.cov_k).ldlt().solve(dp)) < 1.0) {
        if (i + 1 == c->hypotheses.size()) c->farthest_alive = false;
        continue;
      }
      kept.push_back(h);
    }
    c->hypotheses = std::move(kept);
  }
  // SPRT against the best other hypothesis.
  const double prune = std::log(options_.sprt_missed_detection / (1 - options_.sprt_false_alarm));
  const double accept = std::log((1 - options_.sprt_missed_detection) / options_.sprt_false_alarm);
  const int n = static_cast<int>(c->hypotheses.size());
  int winner = n == 1 ? 0 : -1;
  std::vector<bool> keep(n, true);
  if (n > 1) {
    for (int i = 0; i < n; ++i) {
      double best_other = -std::numeric_limits<double>::infinity();
      for (int k = 0; k < n; ++k) {
        if (k != i) best_other = std::max(best_other, c->hypotheses[k].log_likelihood);
      }
      const double llr = c->hypotheses[i].log_likelihood - best_other;
      if (llr > accept) winner = i;
      if (llr < prune) keep[i] = false;
    }
    if (winner < 0) {
      std::vector<Hypothesis> kept;
      for (int i = 0; i < n; ++i) {
        if (keep[i]) {
          kept.push_back(c->hypotheses[i]);
        } else if (i == n - 1) {
          c->farthest_alive = false;
        }
      }
      c->hypotheses = std::move(kept);
      if (c->hypotheses.size() == 1) winner = 0;
    }
  }
  if (c->hypotheses.empty()) {
    rejected_.insert(id);
    ++stats_.dropped;
    return false;
  }
  if (winner >= 0) {
    if (state_.full() && !MakeRoom()) return true;  // Wait for room.
    if (InsertLandmark(id, *c, c->hypotheses[winner])) {
      ++stats_.inserted;
    } else {
      rejected_.insert(id);
      ++stats_.dropped;
    }
    return false;
  }
  return true;
}

Matrix6d MonoEkfEstimator::RelativeCovariance(int j) const {
  // T_j_c = M_{j+1} ... M_c with M_m = M_hat_m Exp(eta_m): moving each Exp(eta_m) to the right,
  // Sigma_jc = sum_m Adj(B_m^-1) Q_m Adj(B_m^-1)^T, B_m = M_{m+1} ... M_c; then
  // T_c_j = T_j_c^-1, whose right perturbation is -Adj(T_j_c) delta.
  Pose B = Pose::Identity();
  Matrix6d sigma = Matrix6d::Zero();
  for (int m = frame_index_; m > j; --m) {
    const PoseRecord& rec = pose_buffer_.at(m);
    const Matrix6d A = AdjointSE3(B.inverse());
    sigma += A * rec.motion_cov * A.transpose();
    B = rec.T_prev_cur * B;
  }
  const Matrix6d A = AdjointSE3(B);
  return A * sigma * A.transpose();
}

bool MonoEkfEstimator::InsertLandmark(LandmarkId id, const Candidate& c, const Hypothesis& h) {
  const Pose& T_w_c = state_.T_w_c();
  const Pose T_c_w = T_w_c.inverse();
  // Prior: the winning hypothesis moved into the current camera.
  const auto first = pose_buffer_.find(c.first_frame);
  if (first == pose_buffer_.end()) return false;
  const Pose T_c_k = T_c_w * first->second.T_w_c;
  const Eigen::Matrix3d R_c_k = T_c_k.linear();
  const Eigen::Vector3d p_k = h.s * c.b_c;
  const Eigen::Vector3d x0 = T_c_k * p_k;
  Eigen::Matrix<double, 3, 6> J;
  J << -R_c_k * Skew(p_k), R_c_k;
  const Eigen::Matrix3d prior_cov =
      R_c_k * (c.b_c * (h.sigma * h.sigma) * c.b_c.transpose() + h.s * h.s * c.cov_b_c) *
          R_c_k.transpose() +
      J * RelativeCovariance(c.first_frame) * J.transpose();
  const Eigen::Matrix3d prior_info = prior_cov.inverse();

  // Observations j: T_c_j and the uncertainty of that relative pose.
  struct Replay {
    Pose T_c_j;
    Matrix6d cov;
    const StoredObservation* obs;
  };
  std::vector<Replay> replay;
  for (size_t k = 1; k < c.observations.size(); ++k) {
    const auto it = pose_buffer_.find(c.observations[k].frame);
    if (it == pose_buffer_.end()) continue;
    replay.push_back({T_c_w * it->second.T_w_c, RelativeCovariance(it->first), &c.observations[k]});
  }
  const double n_replay = std::max<double>(1.0, static_cast<double>(replay.size()));
  // Gauss-Newton on the prior and the replayed observations (an iterated EKF of the point).
  Eigen::Vector3d x = x0;
  Eigen::Matrix3d A;
  double cost = 0;
  for (int iteration = 0; iteration < 10; ++iteration) {
    A = prior_info;
    Eigen::Vector3d b = prior_info * (x0 - x);
    cost = (x - x0).dot(prior_info * (x - x0));
    for (const Replay& r : replay) {
      Eigen::Vector2d uv;
      Eigen::Matrix<double, 2, 6> H_T;
      Eigen::Matrix<double, 2, 3> H_x;
      if (!PredictMonoObservation(camera_, r.T_c_j, x, &uv, &H_T, &H_x)) return false;
      const double s2 = r.obs->sigma_px * r.obs->sigma_px;
      // The relative-pose errors of the replayed observations share motion segments (they are
      // strongly correlated); counting each with n times its covariance (covariance
      // intersection) keeps the refined point conservative instead of n times overconfident.
      const Eigen::Matrix2d R_inv =
          (n_replay * H_T * r.cov * H_T.transpose() + s2 * Eigen::Matrix2d::Identity()).inverse();
      const Eigen::Vector2d res = r.obs->uv - uv;
      A += H_x.transpose() * R_inv * H_x;
      b += H_x.transpose() * R_inv * res;
      cost += res.dot(R_inv * res);
    }
    const Eigen::Vector3d dx = A.ldlt().solve(b);
    x += dx;
    if (dx.norm() < 1e-6 * (1 + x.norm())) break;
  }
  // The refined point must agree with its observations (chi2 with 2 dof per observation and 3
  // for the prior; 99.9 % region, about mean + 3 sigma).
  const double dof = 2.0 * static_cast<double>(replay.size()) + 3.0;
  if (cost > dof + 3 * std::sqrt(2 * dof) || !(x.z() > 0)) return false;
  state_.AddLandmarkFromCamera(id, x, A.inverse());
  info_[id] =
      EkfLandmarkInfo{frame_index_, frame_index_, static_cast<int>(c.observations.size()), 0};
  return true;
}

bool MonoEkfEstimator::MakeRoom() {
  const std::vector<int> order =
      EvictionOrder(state_, info_, frame_index_, options_.evict_unseen_frames);
  if (order.empty()) return false;
  std::vector<bool> remove(state_.num_landmarks(), false);
  remove[order.front()] = true;
  info_.erase(state_.id(order.front()));
  state_.RemoveLandmarks(remove);
  return true;
}

namespace {

bool HasMetricMotion(const FrameMeasurement& m) {
  return m.odometry.has_value() || (m.motion.has_value() && m.motion->scale_known);
}

}  // namespace

EstimatorOutput MonoEkfEstimator::Add(const FrameMeasurement& m) {
  ++frame_index_;
  stats_ = {};
  if (prediction_ == Prediction::kUndecided) {
    if (frame_index_ == 0 && !m.stereo && !HasMetricMotion(m)) {
      initializer_->Add(m);  // Frame 0 goes on as in "motion" below, until the next frame.
    } else if (frame_index_ == 0 || HasMetricMotion(m)) {
      prediction_ = Prediction::kMotion;
      initializer_.reset();
    } else {
      SwitchToConstantVelocity();
    }
  }
  if (prediction_ == Prediction::kConstantVelocity) {
    if (initializer_) return AddBeforeInitialization(m);
    double dt = 1e-9 * static_cast<double>(m.t_ns - last_t_ns_);
    if (!(dt > 0)) {
      LOG_FIRST_N(WARNING, 1) << "MonoEkf: timestamps do not increase; the last step is used";
      dt = last_dt_;
    }
    last_t_ns_ = m.t_ns;
    last_dt_ = dt;
    const Pose T_w_prev = state_.T_w_c();
    state_.PredictConstantVelocity(dt, VelocityNoise(dt));
    const std::vector<int> zone_count = UpdateState(m, /*apply_updates=*/true);
    // The pose buffer: the estimated step and the velocity's uncertainty over it.
    PoseRecord record{state_.T_w_c(), state_.pose_covariance()};
    record.T_prev_cur = T_w_prev.inverse() * state_.T_w_c();
    const Matrix6d J = RightJacobianSE3(state_.velocity() * dt) * dt;
    record.motion_cov = J * state_.velocity_covariance() * J.transpose();
    EstimatorOutput out;
    out.valid = stats_.updated > 0;
    ManageMap(m, record, zone_count, &out);
    return out;
  }

  EstimatorOutput out;
  const MotionEstimate* motion = nullptr;
  if (m.odometry.has_value()) {
    motion = &*m.odometry;
  } else if (m.motion.has_value() && m.motion->scale_known) {
    motion = &*m.motion;
  }
  Vector6d lost_var;
  const double sr = options_.lost_rotation_sigma, st = options_.lost_translation_sigma;
  lost_var << sr * sr, sr * sr, sr * sr, st * st, st * st, st * st;
  const Matrix6d lost_cov = lost_var.asDiagonal();
  if (frame_index_ == 0) {
    state_.Reset(Pose::Identity(), Matrix6d::Zero());
    out.valid = true;
  } else if (motion != nullptr) {
    state_.Predict(motion->T_prev_cur, motion->cov);
    out.valid = true;
  } else {
    state_.InflatePose(lost_cov);
    out.valid = false;
  }
  const std::vector<int> zone_count = UpdateState(m, /*apply_updates=*/true);
  PoseRecord record{state_.T_w_c(), state_.pose_covariance()};
  if (frame_index_ > 0 && motion != nullptr) {
    record.T_prev_cur = motion->T_prev_cur;
    record.motion_cov = motion->cov;
  } else if (frame_index_ > 0) {
    record.motion_cov = lost_cov;
  }
  ManageMap(m, record, zone_count, &out);
  return out;
}

std::vector<int> MonoEkfEstimator::UpdateState(const FrameMeasurement& m, bool apply_updates) {
  // EKF update with the landmarks and directions seen in this frame.
  std::vector<EkfUpdateBlock> blocks;
  std::vector<int> zone_count(grid_.size(), 0);
  auto gated = [&](EkfUpdateBlock* b) {
    const Eigen::MatrixXd S = state_.InnovationCovariance(*b);
    const Eigen::LLT<Eigen::MatrixXd> llt(S);
    return llt.info() == Eigen::Success &&
           b->residual.dot(llt.solve(b->residual)) < options_.gate_chi2;
  };
  for (const FeatureObservation& obs : m.observations) {
    const double s2 = obs.sigma_px * obs.sigma_px;
    const int i = state_.IndexOf(obs.landmark);
    if (i >= 0 && !apply_updates) {
      ++zone_count[grid_.Zone(obs.uv)];
      continue;
    }
    if (i >= 0) {
      EkfLandmarkInfo& info = info_.at(obs.landmark);
      Eigen::Vector2d uv;
      Eigen::Matrix<double, 2, 6> H_T;
      Eigen::Matrix<double, 2, 3> H_x;
      EkfUpdateBlock b;
      bool ok = PredictMonoObservation(camera_, state_.T_w_c(), state_.p_w(i), &uv, &H_T, &H_x);
      if (ok) {
        b.residual = obs.uv - uv;
        b.R = s2 * Eigen::Matrix2d::Identity();
        b.H_pose = H_T;
        b.landmark = i;
        b.H_landmark = H_x;
        ok = gated(&b);
      }
      if (ok) {
        blocks.push_back(std::move(b));
        info.last_seen = frame_index_;
        ++info.observations;
        info.gate_failures = 0;
        ++zone_count[grid_.Zone(obs.uv)];
      } else {
        ++info.gate_failures;
        ++stats_.gated_out;
      }
      continue;
    }
    const auto dir = directions_.find(obs.landmark);
    if (dir != directions_.end()) {
      Direction& d = dir->second;
      const Eigen::Matrix3d R_c_w = state_.T_w_c().linear().transpose();
      const Eigen::Vector3d d_c = R_c_w * d.d_w;
      Eigen::Vector2d uv;
      Eigen::Matrix<double, 2, 3> d_uv_d_dc;
      EkfUpdateBlock b;
      bool ok = camera_.Project(d_c, &uv, &d_uv_d_dc);
      if (ok) {
        const Eigen::Matrix<double, 2, 3> H_d = d_uv_d_dc * R_c_w;
        b.residual = obs.uv - uv;
        b.R = s2 * Eigen::Matrix2d::Identity() + H_d * d.cov * H_d.transpose();
        b.H_pose.resize(2, 6);
        b.H_pose << d_uv_d_dc * Skew(d_c), Eigen::Matrix<double, 2, 3>::Zero();
        ok = gated(&b);
      }
      if (ok) {
        blocks.push_back(std::move(b));
        d.last_seen = frame_index_;
        d.gate_failures = 0;
        ++zone_count[grid_.Zone(obs.uv)];
      } else {
        ++d.gate_failures;
        ++stats_.gated_out;
      }
    }
  }
  stats_.updated = static_cast<int>(blocks.size());
  if (!state_.Update(blocks)) LOG(WARNING) << "MonoEkf: singular innovation, update skipped";

  // Removal of unreliable landmarks and directions.
  std::vector<bool> remove(state_.num_landmarks(), false);
  bool any = false;
  for (int i = 0; i < state_.num_landmarks(); ++i) {
    if (info_.at(state_.id(i)).gate_failures >= options_.max_gate_failures) {
      remove[i] = any = true;
      info_.erase(state_.id(i));
    }
  }
  if (any) state_.RemoveLandmarks(remove);
  for (auto it = directions_.begin(); it != directions_.end();) {
    const bool stale = frame_index_ - it->second.last_seen > options_.pose_buffer_size;
    it = (it->second.gate_failures >= options_.max_gate_failures || stale) ? directions_.erase(it)
                                                                           : std::next(it);
  }

  return zone_count;
}

void MonoEkfEstimator::ManageMap(const FrameMeasurement& m, const PoseRecord& record,
                                 std::vector<int> zone_count, EstimatorOutput* out) {
  // Pose buffer for the candidates.
  pose_buffer_[frame_index_] = record;
  while (static_cast<int>(pose_buffer_.size()) > options_.pose_buffer_size) {
    pose_buffer_.erase(pose_buffer_.begin());
  }

  // Candidates: score with the new observation when the image motion is significant.
  std::unordered_map<LandmarkId, const FeatureObservation*> seen;
  for (const FeatureObservation& obs : m.observations) seen[obs.landmark] = &obs;
  for (auto it = candidates_.begin(); it != candidates_.end();) {
    Candidate& c = it->second;
    const auto s = seen.find(it->first);
    bool keep = true;
    if (pose_buffer_.count(c.first_frame) == 0 || frame_index_ - c.last_seen_frame > 1) {
      keep = false;  // Out of the pose buffer, or the track was lost.
    } else if (s != seen.end()) {
      const FeatureObservation& obs = *s->second;
      c.last_seen_frame = frame_index_;
      ++zone_count[grid_.Zone(obs.uv)];
      const double motion2 =
          (obs.uv - c.last_used_uv).squaredNorm() / (2 * obs.sigma_px * obs.sigma_px);
      if (motion2 > options_.min_image_motion_chi2) keep = UpdateCandidate(it->first, &c, obs);
    }
    if (keep && c.farthest_alive &&
        frame_index_ - c.first_frame >= options_.infinity_after_frames) {
      // The parallax never grew: a point at infinity, kept as a direction.
      if (static_cast<int>(directions_.size()) < options_.max_directions) {
        directions_[it->first] = Direction{c.d_w, c.cov_d_w, frame_index_, 0};
      }
      keep = false;
    }
    if (!keep && directions_.count(it->first) == 0 && state_.IndexOf(it->first) < 0) {
      rejected_.insert(it->first);
    }
    it = keep ? std::next(it) : candidates_.erase(it);
  }

  // New candidates where zones lack landmarks.
  const int zones = grid_.size();
  std::vector<std::vector<const FeatureObservation*>> fresh(zones);
  for (const FeatureObservation& obs : m.observations) {
    if (state_.IndexOf(obs.landmark) >= 0 || candidates_.count(obs.landmark) > 0 ||
        directions_.count(obs.landmark) > 0 || rejected_.count(obs.landmark) > 0) {
      continue;
    }
    fresh[grid_.Zone(obs.uv)].push_back(&obs);
  }
  for (int z = 0; z < zones; ++z) {
    auto& f = fresh[z];
    std::sort(f.begin(), f.end(), [](const FeatureObservation* a, const FeatureObservation* b) {
      if (a->track_length != b->track_length) return a->track_length > b->track_length;
      return a->landmark < b->landmark;
    });
    const int n = std::min<int>({static_cast<int>(f.size()), options_.new_per_zone_per_frame,
                                 std::max(0, options_.target_per_zone - zone_count[z])});
    for (int k = 0; k < n; ++k) {
      if (static_cast<int>(candidates_.size()) >= options_.max_candidates) break;
      StartCandidate(*f[k]);
    }
  }

  stats_.candidates = static_cast<int>(candidates_.size());
  for (const auto& [id, c] : candidates_)
    stats_.hypotheses += static_cast<int>(c.hypotheses.size());
  stats_.directions = static_cast<int>(directions_.size());
  FinishEkfFrame(state_, m.t_ns, out, &trajectory_);
}

}  // namespace dala
