#ifndef DALA_BACKEND_MONO_TWO_VIEW_H_
#define DALA_BACKEND_MONO_TWO_VIEW_H_

// Two-view initialisation of a monocular map: the relative pose of two views of one camera and
// the 3D points of their correspondences, up to scale (the map's unit is this first baseline,
// |t| = 1).
//
// Method (ORB-SLAM's model selection, Mur-Artal et al., T-RO 2015, section IV):
//   1. Both models by seeded RANSAC (OpenCV): an essential matrix E (general scene) and a
//      homography H (planar scene, or too little translation for the epipolar geometry).
//   2. Each model is scored on ALL correspondences by its symmetric transfer error, with
//      sigma = sigma_px:
//        S_M = sum_i sum_{both images} rho_M(d_i^2 / sigma^2),
//        rho_M(x) = Gamma - x  if x < T_M  else 0,   Gamma = T_H = 5.99 (chi2 2 dof, 95 %),
//        T_E = 3.84 (chi2 1 dof, 95 %: the epipolar distance is one-dimensional),
//      where d is the point-to-epipolar-line distance (E, via F = K^-T E K^-1) or the transfer
//      distance |x' - H x| (H). Gamma is the same for both so that the scores compare.
//      R_H = S_H / (S_H + S_E) > homography_ratio picks H (the paper's 0.45), else E.
//   3. The pose: E -> the one of its four (R, t) with the most points in front (cv::recoverPose);
//      H -> cv::decomposeHomographyMat (up to four solutions), the one with the most consistent
//      points (in front of both cameras, reprojecting within 2 sigma, whatever their parallax),
//      refused when the second best has more than ambiguity_ratio as many. A plane has two
//      decompositions that both pass; the spurious one carries a larger rotation and so a larger
//      apparent parallax, so counting only the points above min_point_parallax_deg would favour
//      it (a map started mirrored across the plane, whose scale then drifts: measured on the
//      flight preset, seed 2, 3.3x to 0.4x over 127 m).
//   4. Triangulation of the model's inliers (cv::triangulatePoints); a point is good when it is
//      in front of both cameras, reprojects within 2 sigma in both images and its rays meet at
//      more than min_point_parallax_deg.
//   5. Refused as a pure rotation when the rotation that best maps the inliers' reference rays
//      onto their current rays (least squares) leaves them a median angle below
//      min_residual_parallax_deg: what only a translation explains, which noise does not
//      inflate (a homography decomposed from a noisy pure rotation gives an (R, t) whose rays
//      "meet" at a degree or more: measured 1.19 deg median over 54 points on the rotation
//      preset, while the best rotation leaves ~0.1 deg). A lateral translation is partly
//      mimicked by a rotation, hence a bound below min_parallax_deg.
//   6. Accepted only with min_points good points, a median parallax (of the triangulated rays) of
//      at least min_parallax_deg (tiny motions fail here) and good points in at least
//      min_cells cells of a 4x4 image grid (well spread). Otherwise `reason` says which test
//      failed, with the measured value, e.g. "too little parallax: median 0.21 deg < 1 deg".
//
// Frames: x_ref is the reference view, x_cur the current one; T_cur_ref maps reference-camera
// points into the current camera (p_cur = T_cur_ref p_ref), points come in the reference camera.
// Deterministic: OpenCV's RANSAC generator is seeded from options.seed before each model.

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/camera.h"
#include "core/geometry.h"

namespace dala {

struct TwoViewOptions {
  double sigma_px = 1.0;          // Pixel noise of the correspondences.
  // Step 1's sampler of the essential matrix: RANSAC keeps the model with the most
  // correspondences within the threshold; MAGSAC++ (OpenCV's USAC) weighs every correspondence by
  // its likelihood over noise scales. MonoInitializer tries both (see there).
  enum class EssentialSampler { kRansac, kMagsac };
  EssentialSampler essential_sampler = EssentialSampler::kRansac;
  double ransac_confidence = 0.999;
  int ransac_max_iterations = 1000;
  // The order of the correspondences handed to OpenCV's RANSAC (E and H), which is what seeds
  // its draws (core/ransac_order.h): 0 as given.
  uint64_t ransac_order_seed = 0;
  double homography_ratio = 0.45;  // R_H above this selects the homography.
  double ambiguity_ratio = 0.75;   // Homography: second best / best good points above => refused.
  int min_points = 50;             // Good triangulated points.
  double min_parallax_deg = 1.0;   // Median parallax of the good points.
  double min_point_parallax_deg = 0.3;  // A point with less is not triangulated (near infinity).
  double min_residual_parallax_deg = 0.3;  // Below: a pure rotation (step 5).
  int min_cells = 6;               // Of the 4x4 grid over the current image.

  bool IsValid(std::string* why) const;
};

enum class TwoViewModel { kNone, kEssential, kHomography };
const char* TwoViewModelName(TwoViewModel model);

struct TwoViewResult {
  bool ok = false;
  std::string reason;  // Why not, when !ok.
  TwoViewModel model = TwoViewModel::kNone;
  double homography_score_ratio = 0.0;  // R_H.
  // |translation| = 1. Set when ok, and when the pair is refused after a motion was recovered
  // (by the pure-rotation, parallax, spread or point-count tests of steps 5-6: has_motion()).
  Pose T_cur_ref = Pose::Identity();
  bool has_motion() const { return T_cur_ref.translation().norm() > 0.0; }
  // Per correspondence: the triangulated point in the reference camera, when good.
  std::vector<std::optional<Eigen::Vector3d>> p_ref;
  int num_inliers = 0;  // Of the chosen model's RANSAC.
  int num_good = 0;     // Triangulated, in front, consistent.
  double median_parallax_deg = 0.0;    // Of the triangulated rays.
  double residual_parallax_deg = 0.0;  // Beyond the best pure rotation (step 5).
};

// The camera must have no distortion (rectified pixels); uv_ref[i] <-> uv_cur[i].
TwoViewResult InitializeTwoView(const PinholeCamera& camera,
                                const std::vector<Eigen::Vector2d>& uv_ref,
                                const std::vector<Eigen::Vector2d>& uv_cur,
                                const TwoViewOptions& options);

// Step 2's score S_E of the epipolar geometry of a relative pose (F = K^-T [t]x R K^-1) over all
// correspondences, with sigma = sigma_px: higher is better; compares motions on the same data
// whatever model or sampler gave them.
double EpipolarScore(const PinholeCamera& camera, const Pose& T_cur_ref,
                     const std::vector<Eigen::Vector2d>& uv_ref,
                     const std::vector<Eigen::Vector2d>& uv_cur, double sigma_px);

}  // namespace dala

#endif  // DALA_BACKEND_MONO_TWO_VIEW_H_
