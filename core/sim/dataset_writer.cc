#include "core/sim/dataset_writer.h"

#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iomanip>
#include <limits>
#include <opencv2/imgcodecs.hpp>
#include <set>

#include "core/error.h"
#include "core/io/atomic_file.h"
#include "core/io/camera_calibration.h"
#include "core/io/trajectory_io.h"

namespace dala::sim {
namespace {

std::string ImagePath(const std::string& dir, int cam, size_t i) {
  char name[32];
  std::snprintf(name, sizeof(name), "image_%d/%06zu.png", cam, i);
  return dir + "/" + name;
}

// PNG written under a temporary name and renamed, so a folder never holds half an image.
void WritePng(const std::string& path, const cv::Mat& image) {
  const std::string tmp = path + ".tmp.png";
  if (!cv::imwrite(tmp, image)) throw Error() << path << ": cannot write the image";
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) throw Error() << path << ": cannot rename the image into place: " << ec.message();
}

void WriteCalib(const std::string& path, const SyntheticSequence& seq) {
  const PinholeCamera& c = seq.camera();
  const double b = seq.options().stereo ? seq.options().baseline : 0.0;
  WriteFileAtomically(path, [&](std::ostream& os) {
    os << std::setprecision(12);
    for (int k = 0; k < 4; ++k) {
      const double tx = (k % 2 == 1) ? -c.fx * b : 0.0;
      os << "P" << k << ": " << c.fx << " 0 " << c.cx << " " << tx << " 0 " << c.fy << " " << c.cy
         << " 0 0 0 1 0\n";
    }
  });
}

// The raw cameras (with the lens) in every calibration format dala reads.
void WriteCalibrationFiles(const std::string& dir, const SyntheticSequence& seq) {
  const SimOptions& o = seq.options();
  const PinholeCamera& c = seq.camera();
  CameraCalibration calibration;
  RawCamera& cam = calibration.cam0;
  cam.width = c.width;
  cam.height = c.height;
  cam.fx = c.fx;
  cam.fy = c.fy;
  cam.cx = c.cx;
  cam.cy = c.cy;
  cam.model = o.lens == "fisheye" ? LensModel::kFisheye : LensModel::kRadtan;
  const std::vector<double> k = o.LensCoefficients();
  for (int i = 0; i < 5; ++i) cam.distortion[i] = k[i];
  CameraCalibration pair = calibration;
  if (o.stereo) {
    pair.cam1 = cam;
    pair.T_c1_c0 = seq.T_c0_c1().inverse();
  }
  CreateDirectories(dir);
  WriteCameraCalibration(dir + "/opencv.yml", pair, CalibrationFormat::kOpenCv);
  WriteCameraCalibration(dir + "/kalibr.yaml", pair, CalibrationFormat::kKalibr);
  // One camera: the left one.
  WriteCameraCalibration(dir + "/ros_camera_info.yaml", calibration, CalibrationFormat::kRos);
  // dala's own: a rectified pair or one camera with radtan distortion.
  if (o.lens == "pinhole" || (o.lens == "radtan" && !o.stereo)) {
    if (o.stereo) calibration.rectified_baseline = o.baseline;
    WriteCameraCalibration(dir + "/dala.yaml", calibration, CalibrationFormat::kDala);
  }
}

// Points with duplicates (corners shared by adjacent patches, to 1 mm) removed, first kept.
std::vector<Eigen::Vector3d> UniquePoints(const std::vector<Eigen::Vector3d>& points) {
  std::set<std::array<int64_t, 3>> seen;
  std::vector<Eigen::Vector3d> unique;
  for (const Eigen::Vector3d& p : points) {
    const std::array<int64_t, 3> key = {std::llround(p.x() * 1e3), std::llround(p.y() * 1e3),
                                        std::llround(p.z() * 1e3)};
    if (seen.insert(key).second) unique.push_back(p);
  }
  return unique;
}

// Minimal ASCII PLY of points (a private detail of the simulator; core/io has the general
// writer for maps).
void WritePointsPly(const std::string& path, const std::vector<Eigen::Vector3d>& points) {
  WriteFileAtomically(path, [&](std::ostream& os) {
    const std::vector<Eigen::Vector3d> unique = UniquePoints(points);
    os << "ply\nformat ascii 1.0\ncomment dala synthetic scene points, world frame (z up)\n"
       << "element vertex " << unique.size()
       << "\nproperty float x\nproperty float y\nproperty float z\nend_header\n";
    os << std::setprecision(9);
    for (const auto& p : unique) os << p.x() << " " << p.y() << " " << p.z() << "\n";
  });
}

void WriteMarker(const std::string& path, const SyntheticSequence& seq) {
  const SimOptions& o = seq.options();
  const PinholeCamera& c = seq.camera();
  // FileStorage writes in memory; the file itself is written atomically.
  cv::FileStorage fs(".yaml", cv::FileStorage::WRITE | cv::FileStorage::MEMORY);
  fs << "format"
     << "dala-synthetic";
  fs << "version" << 1;
  fs << "preset" << o.preset;
  // FileStorage has no 64-bit integers: the seed is an int when it fits, else a string.
  if (o.seed <= static_cast<uint64_t>(std::numeric_limits<int>::max())) {
    fs << "seed" << static_cast<int>(o.seed);
  } else {
    fs << "seed" << std::to_string(o.seed);
  }
  fs << "width" << c.width << "height" << c.height;
  fs << "fx" << c.fx << "fy" << c.fy << "cx" << c.cx << "cy" << c.cy;
  fs << "baseline" << (o.stereo ? o.baseline : 0.0);
  // The right image's principal point error (not in calib.txt): a rig to test calibration on.
  fs << "right_cx_error_px" << (o.stereo ? o.right_cx_error_px : 0.0);
  fs << "stereo" << static_cast<int>(o.stereo);
  // The lens (pinhole: none); with one, calib.txt holds the raw K and calibration/kalibr.yaml
  // (read by default) the lens.
  fs << "lens" << o.lens;
  fs << "lens_coefficients" << o.LensCoefficients();
  fs << "fps" << o.fps;
  fs << "frames" << static_cast<int>(seq.size());
  fs << "noise_sigma" << o.noise_sigma;
  fs << "motion_blur" << static_cast<int>(o.motion_blur);
  fs << "blur_samples" << o.blur_samples;
  fs << "exposure_fraction" << o.exposure_fraction;
  fs << "brightness_change" << o.brightness_change;
  fs << "texel_density_scale" << o.texel_density_scale;
  fs << "world_frame"
     << "x east, y north, z up; camera x right, y down, z forward";
  const std::string text = fs.releaseAndGetString();
  WriteFileAtomically(path, [&](std::ostream& os) { os << text; });
}

}  // namespace

void WriteSyntheticDataset(const SimOptions& options, const std::string& dir,
                           const SyntheticDatasetOutputs& outputs) {
  const SyntheticSequence seq(options);
  CreateDirectories(dir + "/image_0");
  if (options.stereo) CreateDirectories(dir + "/image_1");
  WriteCalib(dir + "/calib.txt", seq);
  WriteCalibrationFiles(dir + "/calibration", seq);
  WriteFileAtomically(dir + "/times.txt", [&](std::ostream& os) {
    os << std::setprecision(9) << std::fixed;
    for (size_t i = 0; i < seq.size(); ++i) os << SecondsFromNs(seq.t_ns(i)) << "\n";
  });
  WriteTrajectoryKitti(dir + "/poses.txt", seq.ground_truth());
  if (outputs.odometry) {
    WriteTrajectoryTum(
        dir + "/odometry.txt",
        NoisyOdometry(seq.ground_truth(), options.seed, options.odometry_sigma_rot,
                      options.odometry_sigma_trans, options.odometry_sigma_trans_fraction));
  }
  if (outputs.points) WritePointsPly(dir + "/points.ply", seq.scene().points_w);
  for (size_t i = 0; i < seq.size(); ++i) {
    const Frame frame = seq.Render(i);
    WritePng(ImagePath(dir, 0, i), frame.left);
    if (options.stereo) WritePng(ImagePath(dir, 1, i), frame.right);
    if (outputs.progress && outputs.progress_every > 0 &&
        ((i + 1) % outputs.progress_every == 0 || i + 1 == seq.size())) {
      outputs.progress(i + 1, seq.size());
    }
  }
  // The marker last: a folder with synth.yaml is complete.
  WriteMarker(dir + "/synth.yaml", seq);
}

}  // namespace dala::sim
