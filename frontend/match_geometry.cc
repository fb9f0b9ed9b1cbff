#include "frontend/match_geometry.h"

#include <cmath>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>

#include "core/ransac_order.h"

namespace dala {

std::vector<Match> ApplyGeometricCheck(const DetectedImage& a, const DetectedImage& b,
                                       const std::vector<Match>& matches,
                                       const MatcherOptions& options, bool* failed) {
  if (failed != nullptr) *failed = false;
  std::vector<Match> out;
  switch (options.geometric_check) {
    case GeometricCheck::kNone:
      return matches;
    case GeometricCheck::kEpipolarRectified:
      for (const Match& m : matches) {
        const Eigen::Vector2d& pa = a.points[m.i].uv;
        const Eigen::Vector2d& pb = b.points[m.j].uv;
        const double d = pa.x() - pb.x();
        if (std::abs(pa.y() - pb.y()) <= options.epipolar_max_dv && d >= options.min_disparity &&
            d <= options.max_disparity) {
          out.push_back(m);
        }
      }
      return out;
    case GeometricCheck::kFundamental:
    case GeometricCheck::kHomography:
      break;
  }
  const bool homography = options.geometric_check == GeometricCheck::kHomography;
  const size_t min_count = homography ? 4 : 8;
  if (matches.size() < min_count) {
    if (failed != nullptr) *failed = true;
    return out;
  }
  // The matches in the order that seeds OpenCV's draws (core/ransac_order.h).
  const std::vector<int> order = RansacOrder(matches.size(), options.ransac_order_seed);
  std::vector<cv::Point2f> pa, pb;
  pa.reserve(matches.size());
  pb.reserve(matches.size());
  for (const int k : order) {
    const Match& m = matches[static_cast<size_t>(k)];
    pa.emplace_back(static_cast<float>(a.points[m.i].uv.x()),
                    static_cast<float>(a.points[m.i].uv.y()));
    pb.emplace_back(static_cast<float>(b.points[m.j].uv.x()),
                    static_cast<float>(b.points[m.j].uv.y()));
  }
  cv::Mat mask;
  cv::Mat model;
  if (homography) {
    model = cv::findHomography(pa, pb, cv::RANSAC, options.ransac_threshold_px, mask,
                               options.ransac_max_iterations, options.ransac_confidence);
  } else {
    model = cv::findFundamentalMat(pa, pb, cv::FM_RANSAC, options.ransac_threshold_px,
                                   options.ransac_confidence, options.ransac_max_iterations, mask);
  }
  if (model.empty() || mask.total() != matches.size()) {
    if (failed != nullptr) *failed = true;
    return out;
  }
  const std::vector<bool> inlier = MaskInGivenOrder(mask, order);
  for (size_t k = 0; k < matches.size(); ++k) {
    if (inlier[k]) out.push_back(matches[k]);
  }
  return out;
}

}  // namespace dala
