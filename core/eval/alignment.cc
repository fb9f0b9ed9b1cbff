#include "core/eval/alignment.h"

#include <glog/logging.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cctype>
#include <cmath>

namespace dala {

const char* AlignmentTypeName(AlignmentType type) {
  switch (type) {
    case AlignmentType::kNone:
      return "none";
    case AlignmentType::kSE3:
      return "se3";
    case AlignmentType::kSim3:
      return "sim3";
  }
  return "?";
}

bool ParseAlignmentType(const std::string& name, AlignmentType* type) {
  std::string lower = name;
  std::transform(lower.begin(), lower.end(), lower.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  for (AlignmentType t : {AlignmentType::kNone, AlignmentType::kSE3, AlignmentType::kSim3}) {
    if (lower == AlignmentTypeName(t)) {
      *type = t;
      return true;
    }
  }
  return false;
}

Pose Sim3Alignment::Apply(const Pose& T_e_c) const {
  Pose T_g_c = Pose::Identity();
  T_g_c.linear() = T_g_e.linear() * T_e_c.linear();
  T_g_c.translation() = Apply(Eigen::Vector3d(T_e_c.translation()));
  return T_g_c;
}

bool ComputeAlignment(const std::vector<Eigen::Vector3d>& p_e,
                      const std::vector<Eigen::Vector3d>& p_g, AlignmentType type,
                      Sim3Alignment* alignment, std::string* why) {
  CHECK(alignment != nullptr);
  CHECK_EQ(p_e.size(), p_g.size()) << "alignment needs the same number of points on both sides";
  *alignment = Sim3Alignment();
  if (type == AlignmentType::kNone) return true;
  const auto fail = [&](const std::string& message) {
    if (why != nullptr) *why = message;
    return false;
  };
  if (p_e.size() < 3) {
    return fail(std::string(AlignmentTypeName(type)) + " alignment needs at least 3 pairs, got " +
                std::to_string(p_e.size()));
  }
  const Eigen::Index n = static_cast<Eigen::Index>(p_e.size());
  Eigen::Matrix3Xd src(3, n);
  Eigen::Matrix3Xd dst(3, n);
  for (Eigen::Index i = 0; i < n; ++i) {
    src.col(i) = p_e[static_cast<size_t>(i)];
    dst.col(i) = p_g[static_cast<size_t>(i)];
  }
  const Eigen::Vector3d mean_e = src.rowwise().mean();
  if ((src.colwise() - mean_e).squaredNorm() <= 0.0) {
    return fail("all estimated positions are identical: no alignment is defined");
  }
  const bool with_scale = type == AlignmentType::kSim3;
  // A ground truth that does not translate (rotation in place) leaves the Sim(3) scale free:
  // Umeyama then shrinks the estimate onto the ground truth's single position (scale ~0, ATE
  // ~0, what evo's umeyama_alignment also returns). That number would read as a perfect
  // monocular run, so the alignment is refused instead.
  const Eigen::Vector3d mean_g = dst.rowwise().mean();
  const double rms_spread_g = std::sqrt((dst.colwise() - mean_g).squaredNorm() / n);
  if (with_scale && rms_spread_g < 1e-6) {
    return fail(
        "sim3 alignment is undefined: the ground-truth positions do not move (rotation in "
        "place), so a monocular scale cannot be estimated; evaluate with se3 (the estimate's "
        "translation is then judged at its own scale)");
  }
  // umeyama returns the 4x4 [c R | t] with dst ~ c R src + t (det R = +1, reflections excluded).
  const Eigen::Matrix4d T = Eigen::umeyama(src, dst, with_scale);
  const Eigen::Matrix3d cR = T.topLeftCorner<3, 3>();
  const double c = with_scale ? std::cbrt(cR.determinant()) : 1.0;
  if (!(c > 0.0) || !std::isfinite(c)) return fail("Umeyama gave a non-positive scale");
  alignment->scale = c;
  alignment->T_g_e.linear() = cR / c;
  alignment->T_g_e.translation() = T.topRightCorner<3, 1>();
  return true;
}

Trajectory AlignTrajectory(const Trajectory& est, const Sim3Alignment& alignment) {
  Trajectory out;
  out.has_timestamps = est.has_timestamps;
  out.poses.reserve(est.size());
  for (const StampedPose& p : est.poses) out.Add(p.t_ns, alignment.Apply(p.T_w_c));
  return out;
}

}  // namespace dala
