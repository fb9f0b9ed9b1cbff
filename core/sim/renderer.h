#ifndef DALA_CORE_SIM_RENDERER_H_
#define DALA_CORE_SIM_RENDERER_H_

// Renders a Scene through a pinhole camera (no distortion) with a z-buffer.
//
// Method, per patch: with X_c = R_c_w X_w + t_c_w = M [s t 1]^T, M = [a_c b_c o_c], a pixel
// p = (u, v, 1) sees X_c = z K^-1 p, so G p = [s t 1]^T / z with G = M^-1 K^-1: one 3x3 matrix
// gives the patch coordinates (s, t) and the inverse depth 1/z of every pixel. Pass 1 rasterises
// each patch over the bounding box of its near-clipped projection, keeping the nearest 1/z;
// pass 2 samples the winner's texture once per pixel, trilinearly at the mip level set by the
// pixel footprint (the Jacobian of the homography), so far and grazing surfaces do not alias.

#include <opencv2/core.hpp>

#include "core/camera.h"
#include "core/geometry.h"
#include "core/sim/scene.h"

namespace dala::sim {

// radiance: CV_32FC1 intensities (about [0, 255], not clamped). depth (optional): CV_32FC1, the
// z coordinate in the camera frame of the surface seen at each pixel (metres), 0 where the
// pixel sees the sky. T_w_c: camera (x right, y down, z forward) in the world.
void RenderScene(const Scene& scene, const PinholeCamera& camera, const Pose& T_w_c,
                 cv::Mat* radiance, cv::Mat* depth = nullptr);

}  // namespace dala::sim

#endif  // DALA_CORE_SIM_RENDERER_H_
