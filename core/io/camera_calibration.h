#ifndef DALA_CORE_IO_CAMERA_CALIBRATION_H_
#define DALA_CORE_IO_CAMERA_CALIBRATION_H_

// The calibration files people already have, read into one raw (distorted, unrectified) form,
// and the maps that turn raw images into the distortion-free frames every Dataset yields.
//
// Formats, detected by content (ReadCameraCalibration):
//   opencv  cv::FileStorage output of OpenCV's calibration samples ("%YAML:1.0", `camera_matrix`
//           and `distortion_coefficients` as !!opencv-matrix; `fisheye_model: 1` or
//           `distortion_model: fisheye` for the fisheye model; a stereo pair adds
//           `camera_matrix_right`, `distortion_coefficients_right`, `R`, `T` with
//           p_c1 = R p_c0 + T, or the stereo_calib sample's M1 D1 M2 D2 R T in one file)
//   ros     ROS camera_info YAML (camera_calibration's ost.yaml): image_width, image_height,
//           camera_matrix {rows, cols, data}, distortion_model plumb_bob | equidistant,
//           distortion_coefficients, rectification_matrix, projection_matrix (monocular)
//   kalibr  Kalibr camchain YAML: cam0 (and cam1 with T_cn_cnm1), camera_model pinhole,
//           distortion_model radtan | equidistant, intrinsics [fu fv pu pv],
//           distortion_coeffs, resolution [w h]
//   dala    dala's own (core/io/calibration_yaml.h): fx fy cx cy width height [baseline]
//           [k1 k2 p1 p2 k3]; a baseline describes an already rectified pair
//
// Lens models: pinhole radial-tangential (OpenCV plumb bob, k1 k2 p1 p2 k3) and fisheye
// (equidistant / Kannala-Brandt k1..k4, OpenCV's cv::fisheye).

#include <opencv2/core.hpp>
#include <optional>
#include <string>

#include "core/camera.h"
#include "core/geometry.h"

namespace dala {

enum class LensModel { kRadtan, kFisheye };
const char* LensModelName(LensModel model);  // "radtan", "fisheye"

// One raw camera: intrinsics and the lens model of the images as recorded.
struct RawCamera {
  int width = 0, height = 0;  // Pixels.
  double fx = 0, fy = 0, cx = 0, cy = 0;
  LensModel model = LensModel::kRadtan;
  // radtan: k1 k2 p1 p2 k3; fisheye: k1 k2 k3 k4 (the fifth unused).
  Eigen::Matrix<double, 5, 1> distortion = Eigen::Matrix<double, 5, 1>::Zero();

  bool HasDistortion() const { return !distortion.isZero(0.0); }
  cv::Mat K() const;  // 3x3 CV_64F.
  cv::Mat D() const;  // radtan: 1x5, fisheye: 1x4 (CV_64F).
  bool IsValid(std::string* why) const;
};

enum class CalibrationFormat { kOpenCv, kRos, kKalibr, kDala };
const char* CalibrationFormatName(CalibrationFormat format);  // "opencv", "ros", "kalibr", "dala"

struct CameraCalibration {
  std::string path;  // The file read, for messages.
  CalibrationFormat format = CalibrationFormat::kDala;
  RawCamera cam0;
  // An unrectified stereo pair: the right camera and T_c1_c0 (p_c1 = T_c1_c0 p_c0, OpenCV's R, T
  // of stereoCalibrate, Kalibr's T_cn_cnm1).
  std::optional<RawCamera> cam1;
  Pose T_c1_c0 = Pose::Identity();
  // An already rectified pair sharing cam0's intrinsics (dala's own `baseline`): metres, else 0.
  double rectified_baseline = 0;

  bool is_stereo() const { return cam1.has_value() || rectified_baseline > 0; }
};

// Detects the format by content and reads it. Throws dala::Error naming the file and the fix on
// a missing file, an unknown format, an unknown distortion model, a missing key or an invalid
// camera.
CameraCalibration ReadCameraCalibration(const std::string& path);

// The format of a calibration file from its content; throws dala::Error listing the formats.
CalibrationFormat DetectCalibrationFormat(const std::string& path);

// Writes `calibration` in `format`, atomically, in a form ReadCameraCalibration reads back (and
// OpenCV, ROS and Kalibr tools read too). ROS camera_info holds one camera: a pair writes its
// left camera. dala's own format holds no fisheye lens and no unrectified pair: dala::Error.
void WriteCameraCalibration(const std::string& path, const CameraCalibration& calibration,
                            CalibrationFormat format);

// Maps from raw images to the rectified (stereo) or undistorted (mono) images a Dataset yields.
struct Rectification {
  StereoRig rig;  // Of the output images: no distortion; baseline 0 for mono.
  cv::Mat left_map1, left_map2, right_map1, right_map2;  // cv::remap tables; empty: identity.
  // The raw left camera in the rectified left camera frame's terms: T_c0_c0rect (identity for
  // mono and for an already rectified pair). Ground truth of c0 becomes T_w_c0 * T_c0_c0rect.
  Pose T_c0_c0rect = Pose::Identity();
};

// Builds the maps, as the EuRoC reader does: a stereo pair (stereo and calibration.cam1) is
// rectified with cv::stereoRectify / cv::fisheye::stereoRectify (alpha / balance 0: only valid
// pixels, zero disparity at infinity) into a rig of the same image size; a monocular camera
// (or stereo = false) is undistorted with getOptimalNewCameraMatrix /
// fisheye::estimateNewCameraMatrixForUndistortRectify (alpha / balance 0). An already rectified
// pair (rectified_baseline) only needs cam0 without distortion. Throws dala::Error (naming the
// file) when stereo is asked of a monocular calibration, the two cameras use different lens
// models, or the right camera does not end up at +x.
Rectification MakeRectification(const CameraCalibration& calibration, bool stereo);

}  // namespace dala

#endif  // DALA_CORE_IO_CAMERA_CALIBRATION_H_
