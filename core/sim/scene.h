#ifndef DALA_CORE_SIM_SCENE_H_
#define DALA_CORE_SIM_SCENE_H_

// The synthetic world: planar textured patches (parallelograms and triangles) in the world
// frame w (x east, y north, z up; metres), and a sky.

#include <Eigen/Core>
#include <memory>
#include <vector>

#include "core/sim/texture.h"

namespace dala::sim {

// A planar patch X_w(s, t) = o_w + s * a_w + t * b_w, with (s, t) in [0,1]^2 (parallelogram) or
// s, t >= 0, s + t <= 1 (triangle). Its texel coordinates are the affine map
// uv(s, t) = uv_o + s * uv_a + t * uv_b into texture `texture` (which wraps around).
// Two-sided. Intensity = gain * texel (before haze and camera effects).
struct Surface {
  Eigen::Vector3d o_w = Eigen::Vector3d::Zero();
  Eigen::Vector3d a_w = Eigen::Vector3d::UnitX();
  Eigen::Vector3d b_w = Eigen::Vector3d::UnitY();
  bool triangle = false;
  int texture = 0;
  Eigen::Vector2d uv_o = Eigen::Vector2d::Zero();
  Eigen::Vector2d uv_a = Eigen::Vector2d::UnitX();
  Eigen::Vector2d uv_b = Eigen::Vector2d::UnitY();
  float gain = 1.f;
};

struct Scene {
  std::vector<Surface> surfaces;
  std::vector<std::shared_ptr<const Texture>> textures;
  // Sky brightness at the horizon and at the zenith; distant surfaces fade to the horizon
  // brightness with exp(-z / haze_distance).
  float sky_horizon = 205.f;
  float sky_zenith = 150.f;
  double haze_distance = 250.0;
  // True 3D points of the scene (patch corners), for points.ply and tests.
  std::vector<Eigen::Vector3d> points_w;
};

}  // namespace dala::sim

#endif  // DALA_CORE_SIM_SCENE_H_
