#include "core/camera.h"

#include <glog/logging.h>

#include <cmath>
#include <sstream>

namespace dala {
namespace {

constexpr double kMinDepth = 1e-9;

// Radial-tangential distortion of a normalised point xy (see camera.h) and its 2x2 Jacobian.
Eigen::Vector2d Distort(const Eigen::Matrix<double, 5, 1>& dist, const Eigen::Vector2d& xy,
                        Eigen::Matrix2d* d_xd_d_xy) {
  const double k1 = dist[0], k2 = dist[1], p1 = dist[2], p2 = dist[3], k3 = dist[4];
  const double x = xy.x(), y = xy.y();
  const double r2 = x * x + y * y;
  const double radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
  const Eigen::Vector2d xd(x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x),
                           y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y);
  if (d_xd_d_xy != nullptr) {
    // d radial / d r^2, and d r^2 / dx = 2x.
    const double d_radial = k1 + r2 * (2.0 * k2 + 3.0 * k3 * r2);
    (*d_xd_d_xy)(0, 0) = radial + 2.0 * x * x * d_radial + 2.0 * p1 * y + 6.0 * p2 * x;
    (*d_xd_d_xy)(0, 1) = 2.0 * x * y * d_radial + 2.0 * p1 * x + 2.0 * p2 * y;
    (*d_xd_d_xy)(1, 0) = 2.0 * x * y * d_radial + 2.0 * p1 * x + 2.0 * p2 * y;
    (*d_xd_d_xy)(1, 1) = radial + 2.0 * y * y * d_radial + 6.0 * p1 * y + 2.0 * p2 * x;
  }
  return xd;
}

}  // namespace

bool PinholeCamera::Project(const Eigen::Vector3d& p_c, Eigen::Vector2d* uv,
                            Eigen::Matrix<double, 2, 3>* d_uv_d_p) const {
  CHECK(uv != nullptr) << "PinholeCamera::Project: null output";
  const double z = p_c.z();
  if (!(z > kMinDepth)) return false;
  const double inv_z = 1.0 / z;
  const Eigen::Vector2d xy(p_c.x() * inv_z, p_c.y() * inv_z);
  Eigen::Matrix2d d_xd_d_xy = Eigen::Matrix2d::Identity();
  const bool distorted = HasDistortion();
  const Eigen::Vector2d xd =
      distorted ? Distort(distortion, xy, d_uv_d_p ? &d_xd_d_xy : nullptr) : xy;
  *uv = Eigen::Vector2d(fx * xd.x() + cx, fy * xd.y() + cy);
  if (d_uv_d_p != nullptr) {
    // d xy / d p = [1/z 0 -x/z; 0 1/z -y/z] (x, y normalised).
    Eigen::Matrix<double, 2, 3> d_xy_d_p;
    d_xy_d_p << inv_z, 0.0, -xy.x() * inv_z, 0.0, inv_z, -xy.y() * inv_z;
    const Eigen::Matrix2d F = Eigen::Vector2d(fx, fy).asDiagonal();
    *d_uv_d_p = F * d_xd_d_xy * d_xy_d_p;
  }
  return true;
}

Eigen::Vector3d PinholeCamera::Unproject(const Eigen::Vector2d& uv) const {
  const Eigen::Vector2d xd((uv.x() - cx) / fx, (uv.y() - cy) / fy);
  if (!HasDistortion()) return Eigen::Vector3d(xd.x(), xd.y(), 1.0);
  // Solve Distort(xy) = xd by Gauss-Newton (2x2 Newton steps), starting at xy = xd.
  Eigen::Vector2d xy = xd;
  for (int iter = 0; iter < 30; ++iter) {
    Eigen::Matrix2d J;
    const Eigen::Vector2d r = Distort(distortion, xy, &J) - xd;
    if (r.squaredNorm() < 1e-26) break;
    const double det = J.determinant();
    if (std::abs(det) < 1e-12) break;  // Outside the monotonic region: best effort.
    xy -= J.inverse() * r;
  }
  return Eigen::Vector3d(xy.x(), xy.y(), 1.0);
}

bool PinholeCamera::InImage(const Eigen::Vector2d& uv, double border) const {
  return uv.x() >= border && uv.y() >= border && uv.x() <= width - 1 - border &&
         uv.y() <= height - 1 - border;
}

Eigen::Matrix3d PinholeCamera::K() const {
  Eigen::Matrix3d K;
  K << fx, 0.0, cx, 0.0, fy, cy, 0.0, 0.0, 1.0;
  return K;
}

bool PinholeCamera::IsValid(std::string* why) const {
  std::ostringstream os;
  if (width <= 0 || height <= 0) {
    os << "image size " << width << "x" << height << " must be positive";
  } else if (!(fx > 0) || !(fy > 0) || !std::isfinite(fx) || !std::isfinite(fy)) {
    os << "focal lengths fx=" << fx << " fy=" << fy << " must be positive and finite";
  } else if (!std::isfinite(cx) || !std::isfinite(cy)) {
    os << "principal point (" << cx << ", " << cy << ") must be finite";
  } else if (!distortion.allFinite()) {
    os << "distortion coefficients must be finite";
  }
  if (why != nullptr) *why = os.str();
  return os.str().empty();
}

Pose StereoRig::T_c0_c1() const {
  Pose T = Pose::Identity();
  T.translation() = Eigen::Vector3d(baseline, 0.0, 0.0);
  return T;
}

bool StereoRig::ProjectStereo(const Eigen::Vector3d& p_c0, Eigen::Vector3d* uvd,
                              Eigen::Matrix3d* d_uvd_d_p) const {
  CHECK(uvd != nullptr) << "StereoRig::ProjectStereo: null output";
  CHECK(!left.HasDistortion()) << "StereoRig: a rectified rig has no distortion";
  const double z = p_c0.z();
  if (!(z > kMinDepth)) return false;
  const double inv_z = 1.0 / z;
  const double fb = left.fx * baseline;
  *uvd = Eigen::Vector3d(left.fx * p_c0.x() * inv_z + left.cx, left.fy * p_c0.y() * inv_z + left.cy,
                         fb * inv_z);
  if (d_uvd_d_p != nullptr) {
    const double inv_z2 = inv_z * inv_z;
    *d_uvd_d_p << left.fx * inv_z, 0.0, -left.fx * p_c0.x() * inv_z2,  //
        0.0, left.fy * inv_z, -left.fy * p_c0.y() * inv_z2,            //
        0.0, 0.0, -fb * inv_z2;
  }
  return true;
}

bool StereoRig::Triangulate(const Eigen::Vector3d& uvd, Eigen::Vector3d* p_c0,
                            Eigen::Matrix3d* d_p_d_uvd) const {
  CHECK(p_c0 != nullptr) << "StereoRig::Triangulate: null output";
  const double d = uvd.z();
  if (!(d > 0) || !(baseline > 0)) return false;
  const double z = left.fx * baseline / d;
  const double xn = (uvd.x() - left.cx) / left.fx;
  const double yn = (uvd.y() - left.cy) / left.fy;
  *p_c0 = Eigen::Vector3d(xn * z, yn * z, z);
  if (d_p_d_uvd != nullptr) {
    const double d_z_d_d = -z / d;                 // d(fx b / d)/dd = -fx b / d^2.
    *d_p_d_uvd << z / left.fx, 0.0, xn * d_z_d_d,  //
        0.0, z / left.fy, yn * d_z_d_d,            //
        0.0, 0.0, d_z_d_d;
  }
  return true;
}

Eigen::Matrix3d StereoRig::TriangulationCovariance(const Eigen::Vector3d& uvd, double sigma_px,
                                                   double sigma_disparity) const {
  Eigen::Vector3d p_c0;
  Eigen::Matrix3d J;
  CHECK(Triangulate(uvd, &p_c0, &J))
      << "TriangulationCovariance needs a stereo rig and a positive disparity, got d=" << uvd.z();
  const Eigen::Vector3d var(sigma_px * sigma_px, sigma_px * sigma_px,
                            sigma_disparity * sigma_disparity);
  return J * var.asDiagonal() * J.transpose();
}

bool StereoRig::IsValid(std::string* why) const {
  std::string camera_why;
  std::ostringstream os;
  if (!left.IsValid(&camera_why)) {
    os << "left camera: " << camera_why;
  } else if (!(baseline >= 0) || !std::isfinite(baseline)) {
    os << "baseline " << baseline << " must be >= 0 (0 for monocular)";
  } else if (baseline > 0 && left.HasDistortion()) {
    os << "a rectified stereo rig has no distortion";
  }
  if (why != nullptr) *why = os.str();
  return os.str().empty();
}

}  // namespace dala
