#ifndef DALA_CORE_SIM_SYNTHETIC_SEQUENCE_H_
#define DALA_CORE_SIM_SYNTHETIC_SEQUENCE_H_

// A rendered synthetic sequence with exact ground truth: the project's test world.
//
//   dala::sim::SimOptions options;            // rover_loop, stereo, 752x480, fx = 450
//   options.frames = 50;
//   dala::sim::SyntheticSequence seq(options);
//   dala::Frame f = seq.Render(7);            // f.left, f.right, *f.T_w_c0_gt, f.t_ns
//   cv::Mat depth;
//   cv::Mat img = seq.RenderView(seq.T_w_c0(7), &depth);  // clean view + z depth (metres)
//
// World frame: x east, y north, z up (see core/sim/world.h). Camera: x right, y down, z
// forward; the right camera c1 sits at x = +baseline in c0 (T_c0_c1 = translation (b, 0, 0)),
// rectified, same intrinsics. Everything is deterministic from `seed`: the same options give
// bit-identical images. Render() and RenderView() are const and thread-safe.

#include <cstdint>
#include <memory>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "core/geometry.h"
#include "core/sim/renderer.h"
#include "core/sim/world.h"
#include "core/trajectory.h"
#include "core/types.h"

namespace dala::sim {

struct SimOptions {
  // One of PresetNames(): rover_loop, flight, rotation, fast, low_texture, small_loop,
  // false_loop.
  std::string preset = "rover_loop";
  // A recorded camera path to drive instead of the preset's (dala synth --path; core/sim/
  // recorded_path.h): T_w_c of the left camera at increasing times in any world frame, placed
  // on a street lined with buildings, the camera path_camera_height (m) above the ground (slow
  // climbs and descents levelled, PlaceOnStreet).
  // The ground truth is then in the street world's frame. Empty: the preset's world and path.
  std::vector<StampedPose> path;
  double path_camera_height = 1.65;
  // Number of frames; 0 = the preset's default duration times fps (with a path: every frame
  // time within the recording).
  int frames = 0;
  // Seed of everything random: scene layout, textures, image noise, odometry noise.
  uint64_t seed = 1;
  // Image size and pinhole intrinsics (pixels); cx, cy < 0 mean the image centre.
  int width = 752;
  int height = 480;
  double fx = 450.0;
  double fy = 450.0;
  double cx = -1.0;
  double cy = -1.0;
  // Stereo baseline (m); the right camera is at +baseline along the left camera's x axis.
  double baseline = 0.4;
  // A rectification error to test against: the right image is rendered with its principal
  // point this many pixels right of the rig's (calib.txt still gives the exact, shared cx), so
  // every disparity u_l - u_r comes out this much too small (KITTI 06's rig: ~0.3 px;
  // docs/backend.md, "The rig's disparity offset"). 0: an exact rig.
  double right_cx_error_px = 0.0;
  // Frame rate (Hz): frame i is at t = i / fps.
  double fps = 10.0;
  // Render the right image too.
  bool stereo = true;
  // Standard deviation of the additive Gaussian image noise (grey levels, 0 = none).
  double noise_sigma = 1.0;
  // Motion blur: average of renders at poses spread over an exposure of `exposure_fraction`
  // of the frame interval, centred on the frame time (the ground-truth pose). blur_samples = 0
  // chooses the number from the image motion during the exposure (about one render per
  // 3 pixels of motion, 2..12) so the blur is smooth, not a few ghost copies.
  bool motion_blur = false;
  int blur_samples = 0;
  double exposure_fraction = 0.3;
  // Global brightness change: image gain 1 + brightness_change * sin(2 pi t / 6.3 s + phase),
  // phase from the seed; the right camera's gain differs by a further +2% of it. 0 = constant.
  double brightness_change = 0.0;
  // Noisy odometry (see NoisyOdometry): per-step noise, rotation sigma (rad) and translation
  // sigma (m) plus a fraction of the step's length.
  double odometry_sigma_rot = 0.002;
  double odometry_sigma_trans = 0.005;
  double odometry_sigma_trans_fraction = 0.02;
  // Lens of the rendered images: "pinhole" (none), "radtan" (OpenCV plumb bob, k1 k2 p1 p2 k3)
  // or "fisheye" (equidistant / Kannala-Brandt k1..k4, cv::fisheye), both cameras alike. fx fy
  // cx cy above are then the raw camera's; each image is rendered through a pinhole canvas wide
  // enough for the lens's field of view and warped through the lens (before noise), so the
  // frames are what a real distorting lens gives. Ground truth is of the raw left camera.
  std::string lens = "pinhole";
  // The lens's coefficients (radtan: 4 or 5, fisheye: 4); empty: typical values (radtan
  // -0.28 0.07 2e-4 2e-5 0, EuRoC's cam0; fisheye 0.02 -0.01 0.005 -0.001).
  std::vector<double> lens_coefficients;
  // Side of the procedural textures (power of two); smaller builds faster, looks coarser.
  int texture_size = 1024;
  // Texels per metre on every surface, times this (1: walls 60, ground 80, terrain 12). A
  // surface nearer than f / (60 texels/m) (12 m at f = 707 px) shows each texel over more than
  // a pixel, interpolated bilinearly: smooth where a real wall has finer detail, and Harris
  // corners on it move as the camera approaches (docs/monocular.md, "Scale drift"). 4 keeps a
  // texel under a pixel down to 3 m at f = 707; the texture then repeats every 4.3 m of wall.
  double texel_density_scale = 1.0;

  bool IsValid(std::string* why) const;
  // Effective principal point.
  double cx_or_centre() const { return cx >= 0 ? cx : (width - 1) / 2.0; }
  double cy_or_centre() const { return cy >= 0 ? cy : (height - 1) / 2.0; }
  // The lens coefficients in effect (the defaults when lens_coefficients is empty; 5 numbers,
  // fisheye's fifth 0); all zero for "pinhole".
  std::vector<double> LensCoefficients() const;
};

// Names of the presets, in a fixed order.
std::vector<std::string> PresetNames();

class SyntheticSequence {
 public:
  // Throws dala::Error naming the option when options.IsValid() is false.
  explicit SyntheticSequence(const SimOptions& options);

  const SimOptions& options() const { return options_; }
  size_t size() const { return static_cast<size_t>(frames_); }
  const PinholeCamera& camera() const { return camera_; }
  // The rectified rig of the sequence (baseline 0 when rendered mono). With a lens (options
  // .lens), the raw camera's intrinsics: the images need undistorting first (the calibration
  // files `dala synth` writes describe the lens).
  StereoRig rig() const {
    StereoRig rig;
    rig.left = camera_;
    rig.baseline = options_.stereo ? options_.baseline : 0.0;
    return rig;
  }
  // The 3x3 intrinsic matrix K (same for both cameras).
  Eigen::Matrix3d K() const;
  // T_c0_c1: the right camera in the left camera frame.
  Pose T_c0_c1() const;

  // Frame i: images (with noise, blur, brightness as configured), time and ground truth.
  Frame Render(size_t i) const;
  Pose T_w_c0(size_t i) const;
  int64_t t_ns(size_t i) const;
  // Left-camera pose at any time t (closed form), for tests that need a continuous path.
  Pose T_w_c0_at(double t_s) const { return world_.path->T_w_c(t_s); }
  const Trajectory& ground_truth() const { return ground_truth_; }
  double PathLength() const { return ground_truth_.PathLength(); }

  // Renders a clean view (no noise, blur, brightness change or lens) from any camera pose T_w_c
  // with the sequence's intrinsics; CV_8UC1. depth (optional): CV_32FC1 z in the camera frame
  // (metres) of the surface seen at each pixel, 0 where the pixel sees the sky.
  cv::Mat RenderView(const Pose& T_w_c, cv::Mat* depth = nullptr) const;

  // The scene (patches, textures, true 3D points).
  const Scene& scene() const { return world_.scene; }

 private:
  cv::Mat RenderCamera(size_t i, int cam) const;
  // The lens: the canvas pinhole camera the scene is rendered with, and the cv::remap tables
  // from the canvas to the raw image (empty without a lens).
  void BuildLens();

  SimOptions options_;
  int frames_ = 0;
  PinholeCamera camera_;
  PinholeCamera canvas_;  // = camera_ without a lens.
  cv::Mat lens_map_x_, lens_map_y_;
  World world_;
  Trajectory ground_truth_;
};

// Integrated noisy odometry: the relative poses T_{i-1,i} of `ground_truth` each perturbed on
// the right by Exp([n_rot; n_trans]), n_rot ~ N(0, sigma_rot^2 I), n_trans ~ N(0, (sigma_trans
// + fraction * |step|)^2 I), then chained from the first true pose. Deterministic from seed.
Trajectory NoisyOdometry(const Trajectory& ground_truth, uint64_t seed, double sigma_rot,
                         double sigma_trans, double sigma_trans_fraction);

}  // namespace dala::sim

#endif  // DALA_CORE_SIM_SYNTHETIC_SEQUENCE_H_
