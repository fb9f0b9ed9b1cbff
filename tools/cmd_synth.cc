// `dala synth`: renders a synthetic sequence with exact ground truth into a KITTI-like folder.

#include <gflags/gflags.h>

#include <iostream>
#include <sstream>

#include "core/error.h"
#include "core/io/trajectory_io.h"
#include "core/sim/dataset_writer.h"
#include "core/sim/synthetic_sequence.h"
#include "core/sim/world.h"
#include "tools/command.h"

DECLARE_string(out);  // tools/common_flags.cc
DECLARE_double(fps);  // tools/common_flags.cc
DEFINE_string(preset, "rover_loop",
              "scene and camera path: rover_loop, flight, rotation, fast, low_texture, small_loop, "
              "false_loop");
DEFINE_int32(frames, 0, "number of frames (0 = the preset's default duration x fps)");
DEFINE_uint64(seed, 1, "seed of the scene, textures and noise (same seed -> identical output)");
DEFINE_bool(mono, false, "render the left camera only (no image_1)");
DEFINE_bool(points, false, "also write points.ply (true 3D scene points, world frame)");
DEFINE_bool(odometry, false, "also write odometry.txt (TUM, integrated noisy odometry)");
DEFINE_int32(width, 752, "image width (pixels)");
DEFINE_int32(height, 480, "image height (pixels)");
DEFINE_double(fx, 450.0, "focal length x (pixels)");
DEFINE_double(fy, 450.0, "focal length y (pixels)");
DEFINE_double(noise, 1.0, "standard deviation of the Gaussian image noise (grey levels)");
DEFINE_bool(blur, false, "motion blur (average of sub-frame renders over the exposure)");
DEFINE_double(exposure, 0.5, "exposure time as a fraction of the frame interval (with --blur)");
DEFINE_double(brightness, 0.0,
              "amplitude of the global brightness change (image gain 1 +- this, slow sine)");
DEFINE_double(baseline, 0.4, "stereo baseline (m)");
DEFINE_double(texel_density, 1.0,
              "texels per metre on every surface, times this (1: walls 60/m; 4: detail down to "
              "a pixel at 3 m with fx 707, the texture repeating every 4.3 m)");
DEFINE_double(right_cx_error_px, 0.0,
              "render the right image with its principal point this many pixels off calib.txt's "
              "(every disparity that much too small, as a real rig's rectification error leaves "
              "it; KITTI 06: ~0.3): a rig to test the disparity-offset calibration on");

DEFINE_string(distortion, "",
              "render through a radial-tangential lens: 'radtan' (EuRoC-like k1 -0.28 k2 0.07 "
              "p1 2e-4 p2 2e-5) or its coefficients 'k1,k2,p1,p2[,k3]'; calibration/ then "
              "describes the lens");
DEFINE_string(fisheye, "",
              "render through a fisheye (equidistant, Kannala-Brandt) lens: 'equidistant' "
              "(k 0.02 -0.01 0.005 -0.001) or its coefficients 'k1,k2,k3,k4'");
DEFINE_string(path, "",
              "drive this recorded camera path instead of the preset's (a ground-truth "
              "trajectory: KITTI poses.txt, TUM or EuRoC csv), along streets lined with "
              "buildings; a KITTI file has one pose per frame at --fps");
DEFINE_string(path_format, "auto", "format of --path: auto, kitti, tum, euroc");
DEFINE_int32(path_first, 0, "index of the first pose of --path to drive (a clip from there)");
DEFINE_double(path_camera_height, 1.65,
              "camera height above the street along --path, metres (KITTI's car: 1.65)");

namespace dala {
namespace {

// The recorded path of --path from pose --path_first on (a KITTI file: one pose per frame at
// `fps`); PlaceOnStreet counts its times from its first pose.
std::vector<StampedPose> RecordedPathFlag(double fps) {
  const Trajectory trajectory =
      ReadTrajectory(FLAGS_path, ParseTrajectoryFormat(FLAGS_path_format));
  if (FLAGS_path_first < 0 || FLAGS_path_first + 2 > static_cast<int>(trajectory.size())) {
    throw Error() << "--path_first " << FLAGS_path_first << ": " << FLAGS_path << " has "
                  << trajectory.size() << " poses, and a path needs 2 from the first";
  }
  std::vector<StampedPose> path;
  for (size_t i = static_cast<size_t>(FLAGS_path_first); i < trajectory.size(); ++i) {
    StampedPose p = trajectory.poses[i];
    const size_t k = i - static_cast<size_t>(FLAGS_path_first);
    if (!trajectory.has_timestamps) p.t_ns = NsFromSeconds(static_cast<double>(k) / fps);
    path.push_back(p);
  }
  return path;
}

// "radtan" / "equidistant" (the defaults) or a comma-separated list of numbers.
std::vector<double> LensCoefficientsFlag(const std::string& flag, const std::string& value,
                                         const char* model_name) {
  if (value == model_name) return {};
  std::vector<double> k;
  std::stringstream ss(value);
  std::string item;
  while (std::getline(ss, item, ',')) {
    try {
      size_t used = 0;
      k.push_back(std::stod(item, &used));
      if (used != item.size()) throw std::invalid_argument(item);
    } catch (const std::exception&) {
      throw Error() << "--" << flag << " '" << value << "': expected '" << model_name
                    << "' or comma-separated numbers";
    }
  }
  return k;
}

int RunSynth(const std::vector<std::string>& args) {
  if (!args.empty()) throw Error() << "unexpected argument '" << args[0] << "'; see --help";
  if (FLAGS_out.empty()) throw Error() << "--out is required: the folder to write";
  sim::SimOptions options;
  options.preset = FLAGS_preset;
  options.frames = FLAGS_frames;
  options.seed = FLAGS_seed;
  options.stereo = !FLAGS_mono;
  options.width = FLAGS_width;
  options.height = FLAGS_height;
  options.fx = FLAGS_fx;
  options.fy = FLAGS_fy;
  options.noise_sigma = FLAGS_noise;
  options.motion_blur = FLAGS_blur;
  options.exposure_fraction = FLAGS_exposure;
  options.brightness_change = FLAGS_brightness;
  if (FLAGS_fps < 0) throw Error() << "--fps " << FLAGS_fps << " must be > 0 (0: 10 Hz)";
  if (FLAGS_fps > 0) options.fps = FLAGS_fps;
  options.baseline = FLAGS_baseline;
  options.texel_density_scale = FLAGS_texel_density;
  options.right_cx_error_px = FLAGS_right_cx_error_px;
  if (!FLAGS_path.empty()) {
    options.preset = "path";
    options.path = RecordedPathFlag(options.fps);
    options.path_camera_height = FLAGS_path_camera_height;
  }
  if (!FLAGS_distortion.empty() && !FLAGS_fisheye.empty()) {
    throw Error() << "--distortion and --fisheye are two lenses: give one";
  }
  if (!FLAGS_distortion.empty()) {
    options.lens = "radtan";
    options.lens_coefficients = LensCoefficientsFlag("distortion", FLAGS_distortion, "radtan");
  }
  if (!FLAGS_fisheye.empty()) {
    options.lens = "fisheye";
    options.lens_coefficients = LensCoefficientsFlag("fisheye", FLAGS_fisheye, "equidistant");
  }
  std::string why;
  if (!options.IsValid(&why)) throw Error() << "invalid option: " << why;

  sim::SyntheticDatasetOutputs outputs;
  outputs.points = FLAGS_points;
  outputs.odometry = FLAGS_odometry;
  outputs.progress_every = 50;
  outputs.progress = [](size_t done, size_t total) {
    std::cerr << "dala synth: " << done << "/" << total << " frames\n";
  };
  std::cerr << "dala synth: "
            << (options.path.empty() ? "preset " + options.preset : "path " + FLAGS_path)
            << ", seed " << options.seed << ", " << (options.stereo ? "stereo" : "mono") << " "
            << options.width << "x" << options.height << " -> " << FLAGS_out << "\n";
  sim::WriteSyntheticDataset(options, FLAGS_out, outputs);
  std::cerr << "dala synth: done\n";
  return 0;
}

std::string Usage() {
  std::ostringstream os;
  os << "dala synth --out DIR [--preset NAME] [--frames N] [--seed S] [--mono] [--points] "
        "[--odometry] [--width W --height H] [--noise SIGMA] [--blur] [--brightness A] [--fps HZ]\n"
        "           [--texel_density K] [--path FILE [--path_first I] [--path_camera_height H]]\n"
        "           [--distortion radtan|K1,K2,P1,P2[,K3] | --fisheye equidistant|K1,K2,K3,K4] "
        "...\n\n"
        "Renders a synthetic sequence of a procedural textured world with exact ground truth\n"
        "into a KITTI-like folder: image_0/ (left), image_1/ (right), calib.txt, times.txt,\n"
        "poses.txt (T_w_c0), synth.yaml, optional points.ply and odometry.txt, and calibration/\n"
        "with the cameras in each calibration format `dala run --calibration` reads (OpenCV,\n"
        "Kalibr, ROS camera_info, dala's own). With --distortion or --fisheye the images are\n"
        "rendered through that lens; `dala run` then undistorts them with "
        "calibration/kalibr.yaml.\n"
        "With --path the camera drives a recorded trajectory (e.g. a KITTI drive's poses.txt)\n"
        "through streets lined with buildings along it instead of a preset's path.\n"
        "World frame: x east, y north, z up. See docs/synthetic.md.\n\npresets:\n";
  for (const auto& p : sim::Presets()) {
    os << "  " << p.name << std::string(p.name.size() < 12 ? 12 - p.name.size() : 1, ' ')
       << p.summary << " (" << p.duration_s << " s)\n";
  }
  return os.str();
}

const CommandRegistrar registrar({"synth", "render a synthetic sequence with ground truth", Usage(),
                                  &RunSynth, __FILE__});

}  // namespace
}  // namespace dala
