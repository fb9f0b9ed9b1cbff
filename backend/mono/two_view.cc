#include "backend/mono/two_view.h"

#include <glog/logging.h>

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>
#include <sstream>

#include "core/ransac_order.h"

namespace dala {
namespace {

constexpr double kChi2Dof1 = 3.84;  // 95 %, one-dimensional epipolar distance.
constexpr double kChi2Dof2 = 5.99;  // 95 %, two-dimensional transfer error; also Gamma.
constexpr double kRadToDeg = 180.0 / M_PI;

std::string Format(const char* what, double value, const char* op, double bound,
                   const char* unit = "") {
  std::ostringstream os;
  os.precision(3);
  os << what << " " << value << unit << " " << op << " " << bound << unit;
  return os.str();
}

// ORB-SLAM's score of an essential matrix (see the header): symmetric epipolar distances.
double ScoreEssential(const Eigen::Matrix3d& F, const std::vector<Eigen::Vector2d>& a,
                      const std::vector<Eigen::Vector2d>& b, double inv_sigma2) {
  double score = 0.0;
  for (size_t i = 0; i < a.size(); ++i) {
    const Eigen::Vector3d x1 = a[i].homogeneous(), x2 = b[i].homogeneous();
    const Eigen::Vector3d l2 = F * x1, l1 = F.transpose() * x2;
    const double num = x2.dot(l2);
    const double d2 = num * num / std::max(l2.head<2>().squaredNorm(), 1e-30) * inv_sigma2;
    const double d1 = num * num / std::max(l1.head<2>().squaredNorm(), 1e-30) * inv_sigma2;
    if (d2 < kChi2Dof1) score += kChi2Dof2 - d2;
    if (d1 < kChi2Dof1) score += kChi2Dof2 - d1;
  }
  return score;
}

// ORB-SLAM's score of a homography H (x_b ~ H x_a): transfer errors both ways.
double ScoreHomography(const Eigen::Matrix3d& H, const std::vector<Eigen::Vector2d>& a,
                       const std::vector<Eigen::Vector2d>& b, double inv_sigma2) {
  const Eigen::Matrix3d H_inv = H.inverse();
  double score = 0.0;
  for (size_t i = 0; i < a.size(); ++i) {
    const double e2 = (b[i] - (H * a[i].homogeneous()).hnormalized()).squaredNorm() * inv_sigma2;
    const double e1 =
        (a[i] - (H_inv * b[i].homogeneous()).hnormalized()).squaredNorm() * inv_sigma2;
    if (e2 < kChi2Dof2) score += kChi2Dof2 - e2;
    if (e1 < kChi2Dof2) score += kChi2Dof2 - e1;
  }
  return score;
}

// The parallax that decides (see the header): the rotation that best maps the inliers'
// reference rays onto their current rays (least squares, Umeyama without scale), and the median
// angle each ray is left off by it: what only a translation can explain. Independent of the
// model's own R: a homography decomposed from a pure rotation with noise gives an (R, t) whose
// triangulated rays "meet" at a degree or more (measured on the rotation preset: 1.19 deg median
// over 54 points), while the best rotation leaves only the noise.
double ResidualParallaxDeg(const PinholeCamera& camera, const std::vector<Eigen::Vector2d>& a,
                           const std::vector<Eigen::Vector2d>& b, const std::vector<bool>& inlier) {
  const Eigen::Matrix3d K_inv = camera.K().inverse();
  std::vector<Eigen::Vector3d> ref, cur;
  for (size_t i = 0; i < a.size(); ++i) {
    if (!inlier[i]) continue;
    ref.push_back((K_inv * a[i].homogeneous()).normalized());
    cur.push_back((K_inv * b[i].homogeneous()).normalized());
  }
  if (ref.size() < 3) return 0.0;
  Eigen::Matrix3Xd src(3, ref.size()), dst(3, cur.size());
  for (size_t k = 0; k < ref.size(); ++k) {
    src.col(k) = ref[k];
    dst.col(k) = cur[k];
  }
  // Rays are directions: no centroid to remove. Rotation = the orthogonal Procrustes solution.
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(dst * src.transpose(),
                                              Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d D = Eigen::Matrix3d::Identity();
  D(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0 ? -1.0 : 1.0;
  const Eigen::Matrix3d R = svd.matrixU() * D * svd.matrixV().transpose();
  std::vector<double> angle;
  for (size_t k = 0; k < ref.size(); ++k) {
    angle.push_back(std::acos(std::clamp((R * ref[k]).dot(cur[k]), -1.0, 1.0)));
  }
  std::nth_element(angle.begin(), angle.begin() + angle.size() / 2, angle.end());
  return angle[angle.size() / 2] * kRadToDeg;
}

// Triangulation of a candidate (R, t) (x_cur = R x_ref + t) over the inliers.
struct Reconstruction {
  Pose T_cur_ref = Pose::Identity();
  std::vector<std::optional<Eigen::Vector3d>> p_ref;
  int num_good = 0;
  int num_consistent = 0;  // In front of both cameras and reprojecting within 2 sigma.
  double median_parallax_deg = 0.0;  // Of the points in front and consistent (any parallax).
  int cells = 0;
};

Reconstruction Reconstruct(const PinholeCamera& camera, const Eigen::Matrix3d& R,
                           const Eigen::Vector3d& t, const std::vector<Eigen::Vector2d>& a,
                           const std::vector<Eigen::Vector2d>& b, const std::vector<bool>& inlier,
                           const TwoViewOptions& options) {
  Reconstruction rec;
  rec.T_cur_ref = MakePose(R, t.normalized());
  rec.p_ref.assign(a.size(), std::nullopt);
  const Eigen::Matrix3d K = camera.K();
  Eigen::Matrix<double, 3, 4> P1 = Eigen::Matrix<double, 3, 4>::Zero();
  P1.leftCols<3>() = K;
  Eigen::Matrix<double, 3, 4> P2;
  P2.leftCols<3>() = K * rec.T_cur_ref.linear();
  P2.col(3) = K * rec.T_cur_ref.translation();
  std::vector<int> index;
  cv::Mat pts1(2, 0, CV_64F), pts2(2, 0, CV_64F);
  std::vector<cv::Point2d> c1, c2;
  for (size_t i = 0; i < a.size(); ++i) {
    if (!inlier[i]) continue;
    index.push_back(static_cast<int>(i));
    c1.emplace_back(a[i].x(), a[i].y());
    c2.emplace_back(b[i].x(), b[i].y());
  }
  if (index.empty()) return rec;
  cv::Mat P1_cv, P2_cv, X;
  cv::eigen2cv(P1, P1_cv);
  cv::eigen2cv(P2, P2_cv);
  cv::triangulatePoints(P1_cv, P2_cv, c1, c2, X);  // 4 x N, CV_64F for double input.
  X.convertTo(X, CV_64F);
  const Eigen::Vector3d O2 = -rec.T_cur_ref.linear().transpose() * rec.T_cur_ref.translation();
  const double max_e2 = 4.0 * options.sigma_px * options.sigma_px;  // 2 sigma.
  const double min_point_parallax = options.min_point_parallax_deg / kRadToDeg;
  std::vector<double> parallax;
  bool cell_used[16] = {};
  for (size_t k = 0; k < index.size(); ++k) {
    const double w = X.at<double>(3, static_cast<int>(k));
    if (!std::isfinite(w) || std::abs(w) < 1e-12) continue;
    const Eigen::Vector3d p(X.at<double>(0, static_cast<int>(k)) / w,
                            X.at<double>(1, static_cast<int>(k)) / w,
                            X.at<double>(2, static_cast<int>(k)) / w);
    const Eigen::Vector3d p_cur = rec.T_cur_ref * p;
    if (!p.allFinite() || p.z() <= 0 || p_cur.z() <= 0) continue;
    const int i = index[k];
    Eigen::Vector2d uv1, uv2;
    if (!camera.Project(p, &uv1) || !camera.Project(p_cur, &uv2)) continue;
    if ((uv1 - a[i]).squaredNorm() > max_e2 || (uv2 - b[i]).squaredNorm() > max_e2) continue;
    const double cos_parallax =
        std::clamp(p.normalized().dot((p - O2).normalized()), -1.0, 1.0);
    const double angle = std::acos(cos_parallax);
    parallax.push_back(angle);
    ++rec.num_consistent;
    if (angle < min_point_parallax) continue;
    rec.p_ref[i] = p;
    ++rec.num_good;
    const int cx = std::clamp(static_cast<int>(b[i].x() * 4 / camera.width), 0, 3);
    const int cy = std::clamp(static_cast<int>(b[i].y() * 4 / camera.height), 0, 3);
    cell_used[cy * 4 + cx] = true;
  }
  rec.cells = static_cast<int>(std::count(std::begin(cell_used), std::end(cell_used), true));
  if (!parallax.empty()) {
    std::nth_element(parallax.begin(), parallax.begin() + parallax.size() / 2, parallax.end());
    rec.median_parallax_deg = parallax[parallax.size() / 2] * kRadToDeg;
  }
  return rec;
}

}  // namespace

bool TwoViewOptions::IsValid(std::string* why) const {
  const auto fail = [&](const char* msg) {
    if (why) *why = msg;
    return false;
  };
  if (!(sigma_px > 0)) return fail("mono_init.sigma_px must be > 0");
  if (!(ransac_confidence > 0 && ransac_confidence < 1))
    return fail("mono_init.ransac_confidence must be in (0, 1)");
  if (ransac_max_iterations < 1) return fail("mono_init.ransac_max_iterations must be >= 1");
  if (!(homography_ratio > 0 && homography_ratio < 1))
    return fail("mono_init.homography_ratio must be in (0, 1)");
  if (!(ambiguity_ratio > 0 && ambiguity_ratio <= 1))
    return fail("mono_init.ambiguity_ratio must be in (0, 1]");
  if (min_points < 8) return fail("mono_init.min_points must be >= 8");
  if (!(min_parallax_deg > 0)) return fail("mono_init.min_parallax_deg must be > 0");
  if (!(min_point_parallax_deg >= 0)) return fail("mono_init.min_point_parallax_deg must be >= 0");
  if (!(min_residual_parallax_deg >= 0))
    return fail("mono_init.min_residual_parallax_deg must be >= 0");
  if (min_cells < 1 || min_cells > 16) return fail("mono_init.min_cells must be in [1, 16]");
  return true;
}

const char* TwoViewModelName(TwoViewModel model) {
  switch (model) {
    case TwoViewModel::kNone:
      return "none";
    case TwoViewModel::kEssential:
      return "essential";
    case TwoViewModel::kHomography:
      return "homography";
  }
  return "?";
}

TwoViewResult InitializeTwoView(const PinholeCamera& camera,
                                const std::vector<Eigen::Vector2d>& uv_ref,
                                const std::vector<Eigen::Vector2d>& uv_cur,
                                const TwoViewOptions& options) {
  CHECK_EQ(uv_ref.size(), uv_cur.size()) << "InitializeTwoView needs paired points";
  CHECK(!camera.HasDistortion()) << "InitializeTwoView expects rectified (undistorted) pixels";
  TwoViewResult result;
  const size_t n = uv_ref.size();
  result.p_ref.assign(n, std::nullopt);
  if (static_cast<int>(n) < options.min_points) {
    result.reason = Format("too few correspondences:", static_cast<double>(n), "<",
                           options.min_points);
    return result;
  }
  // The correspondences in the order that seeds OpenCV's draws (core/ransac_order.h).
  const std::vector<int> order = RansacOrder(n, options.ransac_order_seed);
  std::vector<cv::Point2d> a, b;
  for (const int i : order) {
    a.emplace_back(uv_ref[i].x(), uv_ref[i].y());
    b.emplace_back(uv_cur[i].x(), uv_cur[i].y());
  }
  cv::Mat K_cv;
  cv::eigen2cv(camera.K(), K_cv);
  // RANSAC thresholds: the 95 % bounds of one inlier's error (1 dof epipolar, 2 dof transfer).
  const double th_e = options.sigma_px * std::sqrt(kChi2Dof1);
  const double th_h = options.sigma_px * std::sqrt(kChi2Dof2);
  cv::Mat mask_e, mask_h;
  const int e_method = options.essential_sampler == TwoViewOptions::EssentialSampler::kMagsac
                           ? cv::USAC_MAGSAC
                           : cv::RANSAC;
  const cv::Mat E_cv = cv::findEssentialMat(a, b, K_cv, e_method, options.ransac_confidence, th_e,
                                            options.ransac_max_iterations, mask_e);
  const cv::Mat H_cv = cv::findHomography(a, b, cv::RANSAC, th_h, mask_h,
                                          options.ransac_max_iterations,
                                          options.ransac_confidence);
  const double inv_sigma2 = 1.0 / (options.sigma_px * options.sigma_px);
  double score_e = 0.0, score_h = 0.0;
  Eigen::Matrix3d E, H;
  const bool have_e = E_cv.rows == 3 && E_cv.cols == 3;  // 3n x 3 when several solutions.
  const bool have_h = H_cv.rows == 3 && H_cv.cols == 3;
  if (have_e) {
    cv::cv2eigen(E_cv, E);
    const Eigen::Matrix3d K_inv = camera.K().inverse();
    score_e = ScoreEssential(K_inv.transpose() * E * K_inv, uv_ref, uv_cur, inv_sigma2);
  }
  if (have_h) {
    cv::cv2eigen(H_cv, H);
    score_h = ScoreHomography(H, uv_ref, uv_cur, inv_sigma2);
  }
  if (!have_e && !have_h) {
    result.reason = "neither an essential matrix nor a homography fits the correspondences";
    return result;
  }
  result.homography_score_ratio = score_h / std::max(score_h + score_e, 1e-30);
  const bool use_h = !have_e || (have_h && result.homography_score_ratio > options.homography_ratio);

  // The chosen model's RANSAC inliers: what is triangulated and what the parallax tests see.
  const std::vector<bool> inlier = MaskInGivenOrder(use_h ? mask_h : mask_e, order);
  result.num_inliers = static_cast<int>(std::count(inlier.begin(), inlier.end(), true));
  Reconstruction best;
  if (use_h) {
    result.model = TwoViewModel::kHomography;
    std::vector<cv::Mat> Rs, ts, normals;
    cv::decomposeHomographyMat(H_cv, K_cv, Rs, ts, normals);
    int second_consistent = 0;
    for (size_t s = 0; s < Rs.size(); ++s) {
      Eigen::Matrix3d R;
      Eigen::Vector3d t;
      cv::cv2eigen(Rs[s], R);
      cv::cv2eigen(ts[s], t);
      if (t.norm() < 1e-12) continue;
      Reconstruction rec = Reconstruct(camera, R, t, uv_ref, uv_cur, inlier, options);
      if (rec.num_consistent > best.num_consistent) {
        second_consistent = best.num_consistent;
        best = std::move(rec);
      } else {
        second_consistent = std::max(second_consistent, rec.num_consistent);
      }
    }
    if (best.num_consistent > 0 &&
        second_consistent > options.ambiguity_ratio * best.num_consistent) {
      result.num_good = best.num_good;
      result.median_parallax_deg = best.median_parallax_deg;
      result.reason = Format("ambiguous homography: second solution has", second_consistent, ">",
                             options.ambiguity_ratio * best.num_consistent) +
                      " consistent points";
      return result;
    }
  } else {
    result.model = TwoViewModel::kEssential;
    cv::Mat R_cv, t_cv;
    cv::Mat mask = mask_e.clone();
    // recoverPose: the (R, t) of E's four with the most points in front, x_cur = R x_ref + t.
    cv::recoverPose(E_cv, a, b, K_cv, R_cv, t_cv, mask);
    Eigen::Matrix3d R;
    Eigen::Vector3d t;
    cv::cv2eigen(R_cv, R);
    cv::cv2eigen(t_cv, t);
    best = Reconstruct(camera, R, t, uv_ref, uv_cur, inlier, options);
  }
  result.num_good = best.num_good;
  result.median_parallax_deg = best.median_parallax_deg;
  result.T_cur_ref = best.T_cur_ref;  // Also when the tests below refuse the pair.
  // A pure rotation first (see ResidualParallaxDeg), then too little parallax: the usual causes
  // of too few triangulated points.
  result.residual_parallax_deg = ResidualParallaxDeg(camera, uv_ref, uv_cur, inlier);
  if (result.residual_parallax_deg < options.min_residual_parallax_deg) {
    result.reason = Format("too little parallax beyond a pure rotation: median",
                           result.residual_parallax_deg, "<", options.min_residual_parallax_deg,
                           " deg");
    return result;
  }
  if (best.median_parallax_deg < options.min_parallax_deg) {
    result.reason = Format("too little parallax: median", best.median_parallax_deg, "<",
                           options.min_parallax_deg, " deg");
    return result;
  }
  if (best.cells < options.min_cells) {
    result.reason = Format("points not spread: in", best.cells, "<", options.min_cells) +
                    " cells of a 4x4 grid";
    return result;
  }
  if (best.num_good < options.min_points) {
    result.reason = Format("too few triangulated points:", best.num_good, "<", options.min_points);
    return result;
  }
  result.ok = true;
  result.p_ref = std::move(best.p_ref);
  return result;
}

double EpipolarScore(const PinholeCamera& camera, const Pose& T_cur_ref,
                     const std::vector<Eigen::Vector2d>& uv_ref,
                     const std::vector<Eigen::Vector2d>& uv_cur, double sigma_px) {
  const Eigen::Matrix3d K_inv = camera.K().inverse();
  const Eigen::Matrix3d E = Skew(T_cur_ref.translation()) * T_cur_ref.linear();
  return ScoreEssential(K_inv.transpose() * E * K_inv, uv_ref, uv_cur, 1.0 / (sigma_px * sigma_px));
}

}  // namespace dala
