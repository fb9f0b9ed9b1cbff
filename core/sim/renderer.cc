#include "core/sim/renderer.h"

#include <glog/logging.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

namespace dala::sim {
namespace {

constexpr double kNearZ = 0.05;  // Near clipping plane (m).
// Tolerance on the patch coordinates so that adjacent patches leave no cracks.
constexpr double kEdgeEps = 1e-6;

// A patch set up for one view: G maps a pixel (u, v, 1) to [s, t, 1] / z.
struct Setup {
  Eigen::Matrix3d G;
  const Surface* surface;
};

// Clips a convex polygon (camera frame) to z >= kNearZ (Sutherland-Hodgman, one plane).
int ClipNear(const Eigen::Vector3d* in, int n, Eigen::Vector3d* out) {
  int m = 0;
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d& p = in[i];
    const Eigen::Vector3d& q = in[(i + 1) % n];
    const bool p_in = p.z() >= kNearZ, q_in = q.z() >= kNearZ;
    if (p_in) out[m++] = p;
    if (p_in != q_in) {
      const double a = (kNearZ - p.z()) / (q.z() - p.z());
      out[m++] = p + a * (q - p);
    }
  }
  return m;
}

// log2(x) for x >= 1 to ~0.09 accuracy: exponent plus the mantissa's linear part; enough for
// choosing a mip level (continuous and monotonic), and much cheaper than std::log2.
inline float FastLog2(float x) {
  int exponent;
  const float mantissa = std::frexp(x, &exponent);  // x = m 2^e, m in [0.5, 1).
  return static_cast<float>(exponent - 1) + 2.f * (mantissa - 0.5f);
}

// exp(-x) for x >= 0 from a table with linear interpolation (haze is a smooth fade; a 1e-4
// error is invisible after rounding to 8 bits).
class ExpTable {
 public:
  ExpTable() {
    for (int i = 0; i <= kSize; ++i) table_[i] = std::exp(-static_cast<float>(i) / kPerUnit);
  }
  float operator()(float x) const {
    const float f = x * kPerUnit;
    if (f >= kSize) return 0.f;
    const int i = static_cast<int>(f);
    return table_[i] + (f - static_cast<float>(i)) * (table_[i + 1] - table_[i]);
  }

 private:
  static constexpr int kSize = 4096;
  static constexpr float kPerUnit = 256.f;  // Covers x in [0, 16).
  float table_[kSize + 1];
};

}  // namespace

void RenderScene(const Scene& scene, const PinholeCamera& camera, const Pose& T_w_c,
                 cv::Mat* radiance, cv::Mat* depth) {
  CHECK(radiance != nullptr);
  const int W = camera.width, H = camera.height;
  const Pose T_c_w = T_w_c.inverse();
  const Eigen::Matrix3d R_c_w = T_c_w.linear();
  const Eigen::Vector3d t_c_w = T_c_w.translation();
  Eigen::Matrix3d K_inv;
  K_inv << 1.0 / camera.fx, 0, -camera.cx / camera.fx, 0, 1.0 / camera.fy, -camera.cy / camera.fy,
      0, 0, 1;

  // Pass 1: nearest patch per pixel.
  thread_local std::vector<double> inv_z;
  thread_local std::vector<int32_t> winner;
  thread_local std::vector<Setup> setups;
  inv_z.assign(static_cast<size_t>(W) * H, 0.0);
  winner.assign(static_cast<size_t>(W) * H, -1);
  setups.clear();

  Eigen::Vector3d corners[4], clipped[8];
  for (const Surface& surf : scene.surfaces) {
    const Eigen::Vector3d o_c = R_c_w * surf.o_w + t_c_w;
    const Eigen::Vector3d a_c = R_c_w * surf.a_w;
    const Eigen::Vector3d b_c = R_c_w * surf.b_w;
    int n = 0;
    corners[n++] = o_c;
    corners[n++] = o_c + a_c;
    if (!surf.triangle) corners[n++] = o_c + a_c + b_c;
    corners[n++] = o_c + b_c;
    const int m = ClipNear(corners, n, clipped);
    if (m < 3) continue;
    double u_min = 1e300, u_max = -1e300, v_min = 1e300, v_max = -1e300;
    for (int i = 0; i < m; ++i) {
      const double u = camera.fx * clipped[i].x() / clipped[i].z() + camera.cx;
      const double v = camera.fy * clipped[i].y() / clipped[i].z() + camera.cy;
      u_min = std::min(u_min, u), u_max = std::max(u_max, u);
      v_min = std::min(v_min, v), v_max = std::max(v_max, v);
    }
    const int u0 = std::max(0, static_cast<int>(std::floor(u_min)));
    const int u1 = std::min(W - 1, static_cast<int>(std::ceil(u_max)));
    const int v0 = std::max(0, static_cast<int>(std::floor(v_min)));
    const int v1 = std::min(H - 1, static_cast<int>(std::ceil(v_max)));
    if (u0 > u1 || v0 > v1) continue;
    // A plane through the camera centre is seen edge-on: it covers no pixel area.
    const Eigen::Vector3d normal = a_c.cross(b_c);
    if (std::abs(normal.dot(o_c)) < 1e-9 * normal.norm()) continue;
    Eigen::Matrix3d M;
    M.col(0) = a_c, M.col(1) = b_c, M.col(2) = o_c;
    const Eigen::Matrix3d G = M.inverse() * K_inv;
    const int32_t id = static_cast<int32_t>(setups.size());
    setups.push_back({G, &surf});
    const double max_inv_z = 1.0 / kNearZ;
    for (int v = v0; v <= v1; ++v) {
      double* row_inv_z = inv_z.data() + static_cast<size_t>(v) * W;
      int32_t* row_winner = winner.data() + static_cast<size_t>(v) * W;
      // Affine in u along the row.
      double gs = G(0, 0) * u0 + G(0, 1) * v + G(0, 2);
      double gt = G(1, 0) * u0 + G(1, 1) * v + G(1, 2);
      double gw = G(2, 0) * u0 + G(2, 1) * v + G(2, 2);
      for (int u = u0; u <= u1; ++u, gs += G(0, 0), gt += G(1, 0), gw += G(2, 0)) {
        if (gw <= row_inv_z[u] || gw > max_inv_z) continue;
        const double inv = 1.0 / gw;
        const double s = gs * inv, t = gt * inv;
        if (s < -kEdgeEps || t < -kEdgeEps) continue;
        if (surf.triangle ? (s + t > 1.0 + kEdgeEps) : (s > 1.0 + kEdgeEps || t > 1.0 + kEdgeEps)) {
          continue;
        }
        row_inv_z[u] = gw;
        row_winner[u] = id;
      }
    }
  }

  // Pass 2: shade.
  radiance->create(H, W, CV_32FC1);
  if (depth != nullptr) depth->create(H, W, CV_32FC1);
  const Eigen::Matrix3d R_w_c = T_w_c.linear();
  // Sky: brightness from the elevation of the ray d_w = R_w_c K^-1 p.
  const Eigen::Matrix3d RK = R_w_c * K_inv;
  static const ExpTable exp_table;
  const double inv_haze = 1.0 / scene.haze_distance;
  for (int v = 0; v < H; ++v) {
    float* out = radiance->ptr<float>(v);
    float* out_z = depth != nullptr ? depth->ptr<float>(v) : nullptr;
    const double* row_inv_z = inv_z.data() + static_cast<size_t>(v) * W;
    const int32_t* row_winner = winner.data() + static_cast<size_t>(v) * W;
    for (int u = 0; u < W; ++u) {
      const int32_t id = row_winner[u];
      if (id < 0) {
        const Eigen::Vector3d d_w = RK * Eigen::Vector3d(u, v, 1.0);
        const double sin_elev = d_w.z() / d_w.norm();
        const double a = std::clamp(sin_elev, 0.0, 1.0);
        out[u] = static_cast<float>(scene.sky_horizon +
                                    (scene.sky_zenith - scene.sky_horizon) * std::sqrt(a));
        if (out_z) out_z[u] = 0.f;
        continue;
      }
      const Setup& setup = setups[id];
      const Eigen::Matrix3d& G = setup.G;
      const Surface& surf = *setup.surface;
      const double w = row_inv_z[u];
      const double inv = 1.0 / w;
      const double s = (G(0, 0) * u + G(0, 1) * v + G(0, 2)) * inv;
      const double t = (G(1, 0) * u + G(1, 1) * v + G(1, 2)) * inv;
      // d(s)/d(u) = (G00 - s G20) / w etc. (quotient rule on (g0.p)/(g2.p)).
      const double ds_du = (G(0, 0) - s * G(2, 0)) * inv, ds_dv = (G(0, 1) - s * G(2, 1)) * inv;
      const double dt_du = (G(1, 0) - t * G(2, 0)) * inv, dt_dv = (G(1, 1) - t * G(2, 1)) * inv;
      const Eigen::Vector2d duv_du = surf.uv_a * ds_du + surf.uv_b * dt_du;
      const Eigen::Vector2d duv_dv = surf.uv_a * ds_dv + surf.uv_b * dt_dv;
      const double rho2 = std::max(duv_du.squaredNorm(), duv_dv.squaredNorm());
      const float lod = rho2 > 1.0 ? 0.5f * FastLog2(static_cast<float>(rho2)) : 0.f;
      const Eigen::Vector2d uv = surf.uv_o + s * surf.uv_a + t * surf.uv_b;
      const float texel = scene.textures[surf.texture]->Sample(uv.x(), uv.y(), lod);
      const float haze = exp_table(static_cast<float>(inv * inv_haze));
      out[u] = haze * surf.gain * texel + (1.f - haze) * scene.sky_horizon;
      if (out_z) out_z[u] = static_cast<float>(inv);
    }
  }
}

}  // namespace dala::sim
