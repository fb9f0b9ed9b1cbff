#include "frontend/stereo.h"

#include <glog/logging.h>

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <utility>

namespace dala {
namespace {

// Returns the refined right abscissa, or the input when the refinement is not defined.
// The SSD of the left window (centred at uv_left) against the right windows centred at
// (u0 + d, v), d = -1, 0, 1, u0 = round(u_right); the three right windows share their sub-pixel
// row offset, so they are the columns of one (side + 2) x side window sampled once.
double RefineRightAbscissa(const cv::Mat& left_gray, const cv::Mat& right_gray,
                           const Eigen::Vector2d& uv_left, double u_right, int side) {
  const double half = 0.5 * (side - 1);
  if (uv_left.x() - half < 0 || uv_left.y() - half < 0 || uv_left.x() + half > left_gray.cols - 1 ||
      uv_left.y() + half > left_gray.rows - 1) {
    return u_right;
  }
  const double v = uv_left.y();
  const double u0 = std::round(u_right);
  // Every right window must lie inside the image (else the refinement is not defined).
  if (u0 - 1 - half < 0 || v - half < 0 || u0 + 1 + half > right_gray.cols - 1 ||
      v + half > right_gray.rows - 1) {
    return u_right;
  }
  thread_local cv::Mat left_window, right_windows;
  cv::getRectSubPix(left_gray, cv::Size(side, side), cv::Point2f(uv_left.x(), uv_left.y()),
                    left_window, CV_32F);
  cv::getRectSubPix(right_gray, cv::Size(side + 2, side), cv::Point2f(u0, v), right_windows,
                    CV_32F);
  double ssd[3];
  for (int d = 0; d < 3; ++d) {
    ssd[d] = cv::norm(left_window, right_windows(cv::Rect(d, 0, side, side)), cv::NORM_L2SQR);
  }
  const double sm = ssd[0], s0 = ssd[1], sp = ssd[2];
  const double curvature = sm - 2 * s0 + sp;
  // Not a minimum at u0: the match sits on a slope of the SSD, keep the detector's position.
  if (curvature <= 0 || s0 > sm || s0 > sp) return u_right;
  return u0 + 0.5 * (sm - sp) / curvature;
}

}  // namespace

bool StereoOptions::IsValid(std::string* why) const {
  const auto fail = [&](const char* msg) {
    if (why) *why = msg;
    return false;
  };
  if (!matcher.IsValid(why)) return false;
  if (max_dv_px <= 0) return fail("stereo.max_dv_px must be > 0");
  if (min_depth_m <= 0 || (max_depth_m != 0 && max_depth_m <= min_depth_m))
    return fail("stereo: need 0 < min_depth_m < max_depth_m (or max_depth_m 0: no limit)");
  if (!(max_depth_baselines >= 0))
    return fail("stereo.max_depth_baselines must be >= 0 (0: no limit)");
  if (min_points_with_depth < 0) return fail("stereo.min_points_with_depth must be >= 0");
  if (refine_window < 3 || refine_window % 2 == 0)
    return fail("stereo.refine_window must be odd and >= 3");
  if (sigma_px <= 0 || sigma_disparity <= 0) return fail("stereo sigmas must be > 0");
  return true;
}

std::vector<std::optional<StereoPoint>> MatchStereo(const StereoRig& rig, const DetectedImage& left,
                                                    const DetectedImage& right,
                                                    const cv::Mat& left_gray,
                                                    const cv::Mat& right_gray,
                                                    const StereoOptions& options) {
  CHECK(rig.is_stereo()) << "MatchStereo needs a stereo rig";
  const double fb = rig.left.fx * rig.baseline;
  const double min_disparity =
      options.max_depth_m > 0 ? fb / options.max_depth_m : kMinStereoDisparityPx;
  const double max_disparity = fb / options.min_depth_m;
  // Depth is kept from this disparity up (see the depth limit in stereo.h).
  const double min_disparity_kept =
      options.max_depth_baselines > 0
          ? std::max(min_disparity, fb / (options.max_depth_baselines * rig.baseline))
          : min_disparity;
  const MatchPrior prior =
      MatchPrior::RectifiedStereo(options.max_dv_px, min_disparity, max_disparity);
  MatcherOptions matcher = options.matcher;
  matcher.geometric_check = GeometricCheck::kEpipolarRectified;
  matcher.epipolar_max_dv = options.max_dv_px;
  matcher.min_disparity = min_disparity;
  matcher.max_disparity = max_disparity;
  const std::vector<Match> matches = MatchPoints(left, right, matcher, &prior);

  std::vector<std::optional<StereoPoint>> out(left.points.size());
  std::vector<std::pair<double, int>> far;  // (disparity, left index) beyond the depth limit.
  std::vector<Eigen::Vector3d> uvd_of(left.points.size());
  int kept = 0;
  for (const Match& m : matches) {
    const Eigen::Vector2d& uv = left.points[m.i].uv;
    const double u_right = RefineRightAbscissa(left_gray, right_gray, uv, right.points[m.j].uv.x(),
                                               options.refine_window);
    const Eigen::Vector3d uvd(uv.x(), uv.y(), uv.x() - u_right);
    if (uvd.z() < min_disparity || uvd.z() > max_disparity) continue;
    StereoPoint sp;
    sp.u_right = u_right;
    if (!rig.Triangulate(uvd, &sp.p_c0)) continue;
    if (uvd.z() < min_disparity_kept) {
      far.emplace_back(uvd.z(), m.i);
      uvd_of[m.i] = uvd;
      out[m.i] = sp;  // Provisional: removed below unless too few points are near.
      continue;
    }
    sp.cov_p_c0 = rig.TriangulationCovariance(uvd, options.sigma_px, options.sigma_disparity);
    out[m.i] = sp;
    ++kept;
  }
  // Too few near points (an open place, a low-resolution rig) would leave the visual motion
  // without enough 3D-2D correspondences: then the nearest far points keep their depth too, a
  // biased scale being better than a lost frame. Sorted by disparity, then index: deterministic.
  std::sort(far.begin(), far.end(), [](const auto& a, const auto& b) {
    return a.first > b.first || (a.first == b.first && a.second < b.second);
  });
  for (const auto& [disparity, i] : far) {
    if (kept < options.min_points_with_depth) {
      out[i]->cov_p_c0 =
          rig.TriangulationCovariance(uvd_of[i], options.sigma_px, options.sigma_disparity);
      ++kept;
    } else {
      out[i].reset();
    }
  }
  return out;
}

}  // namespace dala
