#ifndef DALA_CORE_IO_EUROC_DATASET_H_
#define DALA_CORE_IO_EUROC_DATASET_H_

// EuRoC ASL folders (the MAV dataset, ETH Zurich):
//   mav0/cam0/data.csv                     "t_ns,filename" per image (a '#' header line)
//   mav0/cam0/data/<t_ns>.png              left raw (distorted) images
//   mav0/cam0/sensor.yaml                  intrinsics [fu fv cu cv], distortion_coefficients
//                                          [k1 k2 p1 p2], T_BS (4x4 row-major, body <- sensor),
//                                          resolution [w h], camera_model pinhole,
//                                          distortion_model radial-tangential
//   mav0/cam1/...                          the right camera, same layout (absent: monocular)
//   mav0/state_groundtruth_estimate0/data.csv   optional ground truth T_w_b:
//                                          t_ns, p xyz, q wxyz, ...
// The given folder may be the one holding mav0/ or mav0/ itself.
//
// Stereo: cam0 and cam1 are rectified with cv::stereoRectify (alpha 0: only valid pixels,
// CALIB_ZERO_DISPARITY) into a rig of the same image size; the maps are built once and each frame
// is remapped. Frames pair cam0 and cam1 images with the same timestamp (exact ns); cam0 images
// without a partner are skipped (logged). Mono (no cam1, or force_mono): cam0 is undistorted.
//
// Ground truth: the csv gives the body (IMU) pose T_w_b. The frames carry the pose of the
// rectified left camera, interpolated at the frame time (InterpolatePose on T_w_b):
//   T_w_c0rect = T_w_b * T_b_c0 * T_c0_c0rect,  T_b_c0 = cam0 T_BS,
//   T_c0_c0rect = [R1^T | 0] with R1 the rectifying rotation of stereoRectify (identity for mono).

#include <string>

#include "core/io/dataset.h"
#include "core/io/image_sequence.h"

namespace dala {

// Throws dala::Error on a malformed folder (see docs/datasets.md) or when
// options.calibration_yaml is set (EuRoC needs its own sensor.yaml files to rectify).
ImageSequence ReadEurocSequence(const std::string& folder, const DatasetOptions& options);

// One camera's sensor.yaml: raw intrinsics with distortion, and T_BS (body <- sensor).
struct EurocCamera {
  PinholeCamera camera;  // Raw intrinsics and distortion.
  Pose T_b_c = Pose::Identity();
};
// Reads a cam<N>/sensor.yaml. Throws dala::Error naming the file and key.
EurocCamera ReadEurocSensorYaml(const std::string& path);

}  // namespace dala

#endif  // DALA_CORE_IO_EUROC_DATASET_H_
