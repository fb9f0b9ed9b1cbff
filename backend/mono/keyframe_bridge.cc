#include "backend/mono/keyframe_bridge.h"

#include <algorithm>

#include "backend/mono/refined_two_view.h"

namespace dala {

std::optional<KeyframeBridge> BridgeFromKeyframe(
    const PinholeCamera& camera, const Pose& T_w_kf,
    const std::map<LandmarkId, BaObservation>& kf_observations, const FrameMeasurement& m,
    double distance, const TwoViewOptions& options, std::string* why) {
  if (!(distance > 0)) {
    if (why) *why = "no speed to scale the step by";
    return std::nullopt;
  }
  std::vector<Eigen::Vector2d> uv_kf, uv_cur;
  for (const FeatureObservation& o : m.observations) {
    const auto it = kf_observations.find(o.landmark);
    if (it == kf_observations.end()) continue;
    uv_kf.push_back(it->second.uv);
    uv_cur.push_back(o.uv);
  }
  const RefinedTwoView pair = SolveRefinedTwoView(camera, uv_kf, uv_cur, options, true);
  if (!pair.two_view.ok) {
    if (why) *why = pair.two_view.reason;
    return std::nullopt;
  }
  const Pose& T_cur_kf = pair.T_cur_ref;  // |t| = 1.
  const std::vector<std::optional<Eigen::Vector3d>>& points = pair.p_ref;
  Pose T_kf_cur = T_cur_kf.inverse();
  T_kf_cur.translation() *= distance;
  KeyframeBridge bridge;
  bridge.T_w_cur = T_w_kf * T_kf_cur;
  bridge.num_points = static_cast<int>(
      std::count_if(points.begin(), points.end(), [](const auto& p) { return p.has_value(); }));
  bridge.median_parallax_deg = pair.two_view.median_parallax_deg;
  return bridge;
}

Matrix6d BridgeInformation(const Pose& T_kf_cur) {
  constexpr double kSigmaRotationRad = 0.01;
  constexpr double kSigmaStepFraction = 0.25;
  const double sigma_t = std::max(kSigmaStepFraction * T_kf_cur.translation().norm(), 1e-6);
  Matrix6d information = Matrix6d::Zero();
  information.topLeftCorner<3, 3>().diagonal().setConstant(1.0 /
                                                           (kSigmaRotationRad * kSigmaRotationRad));
  information.bottomRightCorner<3, 3>().diagonal().setConstant(1.0 / (sigma_t * sigma_t));
  return information;
}

}  // namespace dala
