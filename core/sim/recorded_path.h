#ifndef DALA_CORE_SIM_RECORDED_PATH_H_
#define DALA_CORE_SIM_RECORDED_PATH_H_

// A recorded camera path (a ground-truth trajectory: KITTI poses.txt, TUM, EuRoC) driven again
// through the synthetic street world (`dala synth --path FILE`, docs/synthetic.md).
//
// PlaceOnStreet moves the path into the street world's frame (core/sim/world.h: x east, y
// north, z up, ground z = 0). The path's own world frame may be anything (KITTI's is the first
// camera's: y down, z forward); what is kept is the path's shape:
//   - up: u_w = -normalised mean of the cameras' y axes (the camera y axis points down for a
//     camera looking roughly horizontally, as a car's or a rover's). R_s_w maps u_w to z, the
//     first camera's viewing direction projected on the horizontal plane to x;
//   - positions p_s = R_s_w (p_w - p_w0), their height replaced by camera_height + (h - h_50),
//     h the height along u_w and h_50 its mean over the poses within 25 m of travel either
//     side: the street stays the plane z = 0 under the camera, so a drive's slow climbs and
//     descents (KITTI 00: 3.6 m over 3.7 km) are levelled out while its bumps are kept;
//   - orientations R_s_c = R_s_w R_w_c (pitch and roll as recorded).
// Paths whose cameras do not share a down direction (a handheld camera looking around, a
// drone looking down) cannot be placed on a street: PlaceOnStreet throws dala::Error.
//
// RecordedPath is the CameraPath through the placed poses: slerp of the rotation and linear
// interpolation of the position between the two poses around t (seconds from the first pose),
// held at the first / last pose outside the recording.

#include <vector>

#include "core/sim/world.h"
#include "core/trajectory.h"

namespace dala::sim {

// The path in the street world, times from its first pose (t_ns of pose 0 = 0). Throws
// dala::Error: fewer than 2 poses, times that do not increase, cameras without a shared down
// direction (mean of the y axes' resultant below 0.8), camera_height outside (0, 100] m.
std::vector<StampedPose> PlaceOnStreet(const std::vector<StampedPose>& path, double camera_height);

class RecordedPath : public CameraPath {
 public:
  // `poses`: increasing times (CHECKed), at least one pose.
  explicit RecordedPath(std::vector<StampedPose> poses);
  Pose T_w_c(double t_s) const override;
  double duration_s() const;

 private:
  std::vector<StampedPose> poses_;
};

}  // namespace dala::sim

#endif  // DALA_CORE_SIM_RECORDED_PATH_H_
