// `dala synth`: renders a synthetic sequence with exact ground truth into a KITTI-like folder.

#include <gflags/gflags.h>

#include <iostream>
#include <sstream>

#include "core/error.h"
#include "core/sim/dataset_writer.h"
#include "core/sim/synthetic_sequence.h"
#include "core/sim/world.h"
#include "tools/command.h"

DECLARE_string(out);  // tools/common_flags.cc
DECLARE_double(fps);  // tools/common_flags.cc
DEFINE_string(preset, "rover_loop",
              "scene and camera path: rover_loop, flight, rotation, fast, low_texture, small_loop, false_loop");
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
DEFINE_double(right_cx_error_px, 0.0,
              "render the right image with its principal point this many pixels off calib.txt's "
              "(every disparity that much too small, as a real rig's rectification error leaves "
              "it; KITTI 06: ~0.3): a rig to test the disparity-offset calibration on");

namespace dala {
namespace {

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
  if (FLAGS_fps > 0) options.fps = FLAGS_fps;
  options.baseline = FLAGS_baseline;
  options.right_cx_error_px = FLAGS_right_cx_error_px;
  std::string why;
  if (!options.IsValid(&why)) throw Error() << "invalid option: " << why;

  sim::SyntheticDatasetOutputs outputs;
  outputs.points = FLAGS_points;
  outputs.odometry = FLAGS_odometry;
  outputs.progress_every = 50;
  outputs.progress = [](size_t done, size_t total) {
    std::cerr << "dala synth: " << done << "/" << total << " frames\n";
  };
  std::cerr << "dala synth: preset " << options.preset << ", seed " << options.seed << ", "
            << (options.stereo ? "stereo" : "mono") << " " << options.width << "x" << options.height
            << " -> " << FLAGS_out << "\n";
  sim::WriteSyntheticDataset(options, FLAGS_out, outputs);
  std::cerr << "dala synth: done\n";
  return 0;
}

std::string Usage() {
  std::ostringstream os;
  os << "dala synth --out DIR [--preset NAME] [--frames N] [--seed S] [--mono] [--points] "
        "[--odometry] [--width W --height H] [--noise SIGMA] [--blur] [--brightness A] [--fps HZ] ...\n\n"
        "Renders a synthetic sequence of a procedural textured world with exact ground truth\n"
        "into a KITTI-like folder: image_0/ (left), image_1/ (right), calib.txt, times.txt,\n"
        "poses.txt (T_w_c0), synth.yaml, optional points.ply and odometry.txt.\n"
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
