#ifndef DALA_FRONTEND_MATCHER_H_
#define DALA_FRONTEND_MATCHER_H_

// The robust interest-point matcher of Jung & Lacroix (2001), as used by Lemaire et al. (2007):
// one component for stereo pairs, frame-to-frame tracking, frame-to-keyframe and loop closure.
//
// 1. Candidates by similarity: ZNCC of the rotation- and scale-normalised patches
//    (DetectedImage::descriptors), gated by the auto-correlation attributes (eigenvalue ratio),
//    the scale ratio, optional rotation bounds and the caller's prior; top_k per point, both ways.
// 2. Confirmation by group consistency: a candidate p <-> q with local similarity guess
//    (dtheta = theta_q - theta_p, s = scale_q / scale_p) collects, for each of p's
//    num_neighbours nearest neighbours p', its candidate q' whose displacement q' - q agrees
//    loosely with s R(dtheta) (p' - p). The similarity (phi, sigma) is re-estimated as the median
//    angle and log-scale of those neighbour vectors, and the candidate is confirmed when at least
//    min_support neighbours land within position_tolerance of q + sigma R(phi) (p' - p).
//    Confirmed candidates are made one-to-one greedily (support, then ZNCC).
// 3. Propagation: from each match, the unmatched neighbours p' of p are predicted at
//    q + sigma R(phi)(p' - p); the B points near the prediction are compared by ZNCC of a B patch
//    resampled with the group's rotation and scale (so points with a poor own orientation still
//    match), and the best above propagation_min_zncc is accepted and propagates in turn.
// 4. Geometric check when the caller knows the model: rectified epipolar (|dv|, disparity
//    range), fundamental matrix or homography by OpenCV's RANSAC, whose draws follow the order of
//    the matches (options.ransac_order_seed; core/ransac_order.h).
//
// Usage:
//   DetectedImage a = DetectHarris(img_a, harris), b = DetectHarris(img_b, harris);
//   MatcherOptions options;                         // unconstrained: any rotation, scale <= 2.5
//   options.geometric_check = GeometricCheck::kHomography;
//   std::vector<Match> m = MatchPoints(a, b, options);
//   // Rectified stereo:
//   MatchPrior prior = MatchPrior::RectifiedStereo(/*max_dv=*/2.0, /*min_d=*/0.0, /*max_d=*/150.0);
//   m = MatchPoints(left, right, MatcherOptions::ForStereo(), &prior);
//
// Thread safety: MatchPoints is re-entrant.

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "frontend/harris.h"

namespace dala {

struct Match {
  int i = -1;         // Index into a.points.
  int j = -1;         // Index into b.points.
  float score = 0.f;  // ZNCC of the patches, in [-1, 1].
};

enum class GeometricCheck { kNone, kEpipolarRectified, kFundamental, kHomography };

struct MatcherOptions {
  // Candidates.
  double min_zncc = 0.8;                // ZNCC threshold for a candidate pair.
  int top_k = 3;                        // Candidates kept per point (each way).
  double max_scale_ratio = 2.5;         // Max ratio between the two points' detection scales.
  double max_rotation = 3.2;            // Max |orientation difference| (rad); >= pi: any rotation.
  double max_eigen_ratio_change = 4.0;  // Max factor between the (lambda1/lambda2) of the pair.
  // Group confirmation.
  int num_neighbours = 12;             // Spatial neighbours of p examined.
  int min_support = 4;                 // Neighbours agreeing with one local similarity.
  double loose_angle = 0.5;            // (rad) first, loose agreement with the pair's own guess.
  double loose_scale = 1.6;            // Factor, same.
  double position_tolerance_px = 2.5;  // Final agreement: |q' - prediction| < px + rel*|q'-q|.
  double position_tolerance_rel = 0.1;
  // A match's detection scales must agree with its group's scale sigma:
  // |log(scale_q / scale_p) - log(sigma)| <= log(max_scale_mismatch). Points detected at scales
  // that do not correspond are localised differently (a corner's Harris maximum moves with the
  // integration scale), which costs more than the pixel tolerance.
  double max_scale_mismatch = 1.3;
  // Propagation.
  bool propagate = true;
  double propagation_min_zncc = 0.7;
  double propagation_radius_px = 3.0;  // Search radius around a prediction: px + rel*|q'-q|.
  double propagation_radius_rel = 0.08;
  // Final geometric check.
  GeometricCheck geometric_check = GeometricCheck::kNone;
  double epipolar_max_dv = 2.0;  // kEpipolarRectified: |v_a - v_b| bound (px).
  double min_disparity = 0.0;    // kEpipolarRectified: u_a - u_b range (px).
  double max_disparity = 1e9;
  double ransac_threshold_px = 3.0;  // kFundamental (epipolar distance) / kHomography (reproj.)
  double ransac_confidence = 0.999;
  int ransac_max_iterations = 2000;
  // The order of the matches handed to the kFundamental / kHomography RANSAC, which is what
  // seeds OpenCV's draws (core/ransac_order.h): 0 as matched, N > 0 shuffled with seed N.
  uint64_t ransac_order_seed = 0;

  bool IsValid(std::string* why) const;

  // Presets. Stereo and tracking: small rotation and scale change.
  static MatcherOptions ForStereo();
  static MatcherOptions ForTracking();
};

// What the caller knows about where a point of A lands in B.
struct MatchPrior {
  enum class Type { kNone, kRectifiedStereo, kPredicted };
  Type type = Type::kNone;
  // kRectifiedStereo: |v_a - v_b| <= max_dv and min_disparity <= u_a - u_b <= max_disparity.
  double max_dv = 2.0;
  double min_disparity = 0.0;
  double max_disparity = 1e9;
  // kPredicted: predicted_uv[i] is where a.points[i] should be in B (size a.points.size());
  // a point with a NaN prediction gets no candidate. B points within `radius` of the
  // prediction are allowed.
  std::vector<Eigen::Vector2d> predicted_uv;
  double radius = 20.0;

  static MatchPrior RectifiedStereo(double max_dv, double min_disparity, double max_disparity);
  static MatchPrior Predicted(std::vector<Eigen::Vector2d> predicted_uv, double radius);
  bool Allows(const Eigen::Vector2d& uv_a, int i, const Eigen::Vector2d& uv_b) const;
};

// Counts of each stage, for logs and benchmarks.
struct MatchStats {
  int candidates = 0;
  int confirmed = 0;          // After group confirmation and the one-to-one selection.
  int propagated = 0;         // Added by propagation.
  int after_check = 0;        // Final (after the geometric check).
  bool check_failed = false;  // The geometric model could not be estimated (too few matches).
};

// Matches the points of `a` to those of `b`. One-to-one, sorted by i. CHECK-fails on invalid
// options or a prior inconsistent with `a`. An empty result is a valid answer.
std::vector<Match> MatchPoints(const DetectedImage& a, const DetectedImage& b,
                               const MatcherOptions& options, const MatchPrior* prior = nullptr,
                               MatchStats* stats = nullptr);

}  // namespace dala

#endif  // DALA_FRONTEND_MATCHER_H_
