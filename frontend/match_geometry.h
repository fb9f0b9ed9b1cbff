#ifndef DALA_FRONTEND_MATCH_GEOMETRY_H_
#define DALA_FRONTEND_MATCH_GEOMETRY_H_

// The final, model-based check of the matcher (step 4 of frontend/matcher.h), usable alone.

#include <vector>

#include "frontend/harris.h"
#include "frontend/matcher.h"

namespace dala {

// Keeps the matches consistent with options.geometric_check:
//  kNone: all; kEpipolarRectified: |v_a - v_b| <= epipolar_max_dv and
//  min_disparity <= u_a - u_b <= max_disparity; kFundamental / kHomography: the RANSAC inliers
//  (cv::findFundamentalMat FM_RANSAC / cv::findHomography RANSAC on the matches in the order
//  of RansacOrder(n, options.ransac_order_seed), core/ransac_order.h). When the model cannot be
//  estimated (fewer than 8 / 4 matches or a degenerate set) the result is empty and *failed (if
//  given) is set.
std::vector<Match> ApplyGeometricCheck(const DetectedImage& a, const DetectedImage& b,
                                       const std::vector<Match>& matches,
                                       const MatcherOptions& options, bool* failed = nullptr);

}  // namespace dala

#endif  // DALA_FRONTEND_MATCH_GEOMETRY_H_
