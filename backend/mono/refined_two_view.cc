#include "backend/mono/refined_two_view.h"

#include <glog/logging.h>

#include <algorithm>
#include <cmath>
#include <sstream>

#include "backend/mono/two_view_refinement.h"

namespace dala {
namespace {

RefinedTwoView Solve(const PinholeCamera& camera, const std::vector<Eigen::Vector2d>& uv_ref,
                     const std::vector<Eigen::Vector2d>& uv_cur, TwoViewOptions options,
                     TwoViewOptions::EssentialSampler sampler) {
  options.essential_sampler = sampler;
  RefinedTwoView r;
  r.two_view = InitializeTwoView(camera, uv_ref, uv_cur, options);
  if (!r.two_view.ok) return r;
  r.T_cur_ref = r.two_view.T_cur_ref;
  r.p_ref = r.two_view.p_ref;
  return r;
}

// The two-view BA of an accepted reconstruction (r->two_view.ok).
void Refine(const PinholeCamera& camera, const std::vector<Eigen::Vector2d>& uv_ref,
            const std::vector<Eigen::Vector2d>& uv_cur, const TwoViewOptions& options,
            RefinedTwoView* r) {
  const TwoViewRefinementSummary s =
      RefineTwoView(camera, uv_ref, uv_cur, options.sigma_px, 20, &r->T_cur_ref, &r->p_ref);
  VLOG(1) << "two-view refinement: cost " << s.initial_cost << " -> " << s.final_cost << ", "
          << s.num_points << " points, " << s.num_dropped << " dropped"
          << (s.usable ? "" : " (not usable: kept the unrefined reconstruction)");
}

}  // namespace

double TravelAngleDeg(const Pose& a, const Pose& b) {
  const Eigen::Vector3d ca = -(a.linear().transpose() * a.translation()).normalized();
  const Eigen::Vector3d cb = -(b.linear().transpose() * b.translation()).normalized();
  return std::acos(std::clamp(ca.dot(cb), -1.0, 1.0)) * 180.0 / M_PI;
}

RefinedTwoView SolveRefinedTwoView(const PinholeCamera& camera,
                                   const std::vector<Eigen::Vector2d>& uv_ref,
                                   const std::vector<Eigen::Vector2d>& uv_cur,
                                   const TwoViewOptions& options, bool refine) {
  RefinedTwoView ransac =
      Solve(camera, uv_ref, uv_cur, options, TwoViewOptions::EssentialSampler::kRansac);
  if (ransac.two_view.ok && refine) Refine(camera, uv_ref, uv_cur, options, &ransac);
  if (!ransac.two_view.ok || ransac.two_view.model != TwoViewModel::kEssential) return ransac;
  RefinedTwoView magsac =
      Solve(camera, uv_ref, uv_cur, options, TwoViewOptions::EssentialSampler::kMagsac);
  if (!magsac.two_view.has_motion()) return ransac;
  // MAGSAC++'s motion before its refinement: the two agree (to 0.02-1.6 deg on every pair
  // measured) or are distinct solutions (69-72 deg apart), which refinement does not change;
  // only a distinct one is refined, to be scored.
  double angle = TravelAngleDeg(ransac.T_cur_ref, magsac.two_view.T_cur_ref);
  VLOG(1) << "two-view samplers: directions " << angle << " deg apart"
          << (magsac.two_view.ok ? "" : ", MAGSAC++ refused: " + magsac.two_view.reason);
  if (angle <= kDistinctMotionDeg) return ransac;
  if (magsac.two_view.ok && refine) {
    Refine(camera, uv_ref, uv_cur, options, &magsac);
    angle = TravelAngleDeg(ransac.T_cur_ref, magsac.T_cur_ref);
  }
  const Pose& T_magsac = magsac.two_view.ok ? magsac.T_cur_ref : magsac.two_view.T_cur_ref;
  if (!magsac.two_view.ok) {
    // Two motions fit and the second cannot be reconstructed: wait for a wider pair.
    RefinedTwoView refused = std::move(ransac);
    refused.two_view.ok = false;
    std::ostringstream why;
    why.precision(3);
    why << "two motions fit: MAGSAC++'s direction of travel is " << angle
        << " deg from RANSAC's and its reconstruction refused (" << magsac.two_view.reason << ")";
    refused.two_view.reason = why.str();
    return refused;
  }
  const double score_ransac =
      EpipolarScore(camera, ransac.T_cur_ref, uv_ref, uv_cur, options.sigma_px);
  const double score_magsac = EpipolarScore(camera, T_magsac, uv_ref, uv_cur, options.sigma_px);
  VLOG(1) << "two-view samplers: epipolar score RANSAC " << score_ransac << ", MAGSAC++ "
          << score_magsac;
  if (score_magsac > score_ransac) {
    magsac.magsac = true;
    return magsac;
  }
  return ransac;
}

}  // namespace dala
