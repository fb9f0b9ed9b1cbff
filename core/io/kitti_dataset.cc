#include "core/io/kitti_dataset.h"

#include <cmath>
#include <cstdio>
#include <filesystem>

#include "core/error.h"
#include "core/io/camera_calibration.h"
#include "core/io/text_lines.h"
#include "core/io/trajectory_io.h"

namespace dala {
namespace fs = std::filesystem;
namespace {

std::string ImageName(size_t index) {
  char name[32];
  std::snprintf(name, sizeof(name), "%06zu.png", index);
  return name;
}

size_t CountPngs(const std::string& folder) {
  size_t n = 0;
  for (const auto& entry : fs::directory_iterator(folder)) {
    if (entry.is_regular_file() && entry.path().extension() == ".png") ++n;
  }
  return n;
}

// The rig from calib.txt: left intrinsics from P0, baseline from P1 when stereo.
StereoRig RigFromCalib(const std::string& calib_path, bool stereo) {
  RequireFile(calib_path, "the KITTI calibration with P0 and P1 rows");
  const auto P0 = ReadKittiProjection(calib_path, 0);
  if (!P0) {
    throw Error() << calib_path << ": no 'P0:' row (the left camera's 3x4 projection matrix)";
  }
  StereoRig rig;
  rig.left.fx = (*P0)(0, 0);
  rig.left.fy = (*P0)(1, 1);
  rig.left.cx = (*P0)(0, 2);
  rig.left.cy = (*P0)(1, 2);
  if (std::abs((*P0)(0, 3)) > 1e-9 * std::abs((*P0)(0, 0))) {
    throw Error() << calib_path << ": P0(0,3) = " << (*P0)(0, 3)
                  << " is not 0: P0 must be the reference (left) camera of the rectified pair";
  }
  if (stereo) {
    const auto P1 = ReadKittiProjection(calib_path, 1);
    if (!P1) {
      throw Error() << calib_path << ": no 'P1:' row, but image_1/ exists: add P1 or read the "
                    << "sequence as monocular (force_mono / --mode mono)";
    }
    if (!((*P1)(0, 0) > 0)) {
      throw Error() << calib_path << ": P1(0,0) = " << (*P1)(0, 0)
                    << " is not a focal length; expected fx > 0 (the rectified right camera's "
                       "P1 = [fx 0 cx -fx*baseline; 0 fy cy 0; 0 0 1 0])";
    }
    rig.baseline = -(*P1)(0, 3) / (*P1)(0, 0);
    if (!(rig.baseline > 0)) {
      // P1(0,3) = 0 gives -0: print it as 0.
      throw Error() << calib_path << ": P1 gives baseline " << rig.baseline + 0.0
                    << " m; expected > 0 (P1(0,3) = -fx * baseline, right camera at +x)";
    }
  }
  return rig;
}

std::optional<std::string> FindKittiPoses(const std::string& folder) {
  const fs::path local = fs::path(folder) / "poses.txt";
  if (fs::is_regular_file(local)) return local.string();
  // Official layout: dataset/sequences/NN/ with dataset/poses/NN.txt.
  const fs::path canonical = fs::weakly_canonical(fs::path(folder));
  const fs::path official =
      canonical.parent_path().parent_path() / "poses" / (canonical.filename().string() + ".txt");
  if (fs::is_regular_file(official)) return official.string();
  return std::nullopt;
}

}  // namespace

std::optional<Eigen::Matrix<double, 3, 4>> ReadKittiProjection(const std::string& calib_path,
                                                               int index) {
  const std::string key = "P" + std::to_string(index) + ":";
  for (const NumberedLine& line : ReadDataLines(calib_path, "the KITTI calibration")) {
    const size_t start = line.text.find_first_not_of(" \t");
    if (line.text.compare(start, key.size(), key) != 0) continue;
    NumberedLine values = line;
    values.text = line.text.substr(start + key.size());
    const std::vector<double> v = ParseNumbers(calib_path, values);
    if (v.size() != 12) {
      throw Error() << calib_path << ":" << line.number << ": '" << key << "' has " << v.size()
                    << " numbers, expected 12 (the row-major 3x4 projection matrix)";
    }
    Eigen::Matrix<double, 3, 4> P;
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 4; ++c) P(r, c) = v[4 * r + c];
    }
    return P;
  }
  return std::nullopt;
}

ImageSequence ReadKittiSequence(const std::string& folder, const DatasetOptions& options,
                                DatasetFormat format) {
  RequireFolder(folder, "the sequence folder");
  const std::string left_dir = folder + "/image_0";
  const std::string right_dir = folder + "/image_1";
  RequireFolder(left_dir, "the left images 000000.png, 000001.png, ...");
  const bool stereo = fs::is_directory(right_dir) && !options.force_mono;

  ImageSequence seq;
  seq.format = format;
  seq.path = folder;
  seq.t_ns = ReadTimesFile(folder + "/times.txt");  // Throws on a missing file, bad order.
  const size_t n = seq.t_ns.size();
  // Fewer images than times: the frames without one are checked below (in the range to run).
  const size_t n_images = CountPngs(left_dir);
  if (n_images > n) {
    throw Error() << folder << "/times.txt has " << n << " times but " << left_dir << " holds "
                  << n_images << " PNG images: one time per image is needed";
  }
  const FrameRange range = SelectFrames(n, options, folder);
  std::vector<MissingImage> missing;
  for (size_t i = 0; i < n; ++i) {
    seq.left_files.push_back(left_dir + "/" + ImageName(i));
    if (stereo) seq.right_files.push_back(right_dir + "/" + ImageName(i));
    if (i < range.begin || i >= range.end) continue;
    if (!fs::is_regular_file(seq.left_files.back())) {
      missing.push_back({i, "missing left image '" + seq.left_files.back() +
                                "': images must be numbered 000000.png to " + ImageName(n - 1) +
                                ", one per line of times.txt"});
    } else if (stereo && !fs::is_regular_file(seq.right_files.back())) {
      missing.push_back({i, "missing right image '" + seq.right_files.back() +
                                "' (the left one exists): restore it or read the sequence as "
                                "monocular (force_mono / --mode mono)"});
    }
  }
  CheckMissingImages(missing, range, options, folder);

  // Calibration: the override YAML or calib.txt; the image size from the YAML or the first image
  // of the run.
  const std::string& first_file = seq.left_files[range.begin];
  const cv::Mat first = LoadGrayImage(first_file, cv::Size(), "");
  Pose T_c0_c0rect = Pose::Identity();
  if (!options.calibration_yaml.empty()) {
    T_c0_c0rect = ApplyCalibration(ReadCameraCalibration(options.calibration_yaml), stereo, &seq);
    LoadGrayImage(first_file, seq.raw_size, seq.raw_size_source);
  } else {
    seq.rig = RigFromCalib(folder + "/calib.txt", stereo);
    seq.raw_size = first.size();
    seq.raw_size_source = "the first image " + first_file;
    seq.rig.left.width = first.cols;
    seq.rig.left.height = first.rows;
  }
  std::string why;
  if (!seq.rig.IsValid(&why)) throw Error() << folder << ": invalid calibration: " << why;

  if (const auto poses_path = FindKittiPoses(folder)) {
    const Trajectory gt = ReadTrajectory(*poses_path, TrajectoryFormat::kKitti);
    if (gt.size() < n) {
      throw Error() << *poses_path << " has " << gt.size() << " poses for " << n
                    << " images: the ground truth needs one pose per image";
    }
    for (size_t i = 0; i < n; ++i) seq.T_w_c0_gt.push_back(gt.poses[i].T_w_c * T_c0_c0rect);
  }
  // Optional odometry (TUM: t x y z qx qy qz qw of the left camera), one pose at each image time.
  const std::string odometry_path = folder + "/odometry.txt";
  if (fs::is_regular_file(odometry_path)) {
    const Trajectory odometry = ReadTrajectory(odometry_path, TrajectoryFormat::kTum);
    size_t k = 0;
    for (size_t i = 0; i < n; ++i) {
      // Times match to 1 ms (seconds are written rounded).
      while (k < odometry.size() && odometry.poses[k].t_ns < seq.t_ns[i] - 1000000) ++k;
      if (k == odometry.size() || odometry.poses[k].t_ns > seq.t_ns[i] + 1000000) {
        throw Error() << odometry_path << ": no pose at the time of image " << ImageName(i)
                      << " (" << 1e-9 * static_cast<double>(seq.t_ns[i]) << " s in times.txt): "
                      << "the odometry needs one pose per image time (or remove the file)";
      }
      seq.T_w_odom.push_back(odometry.poses[k].T_w_c);
    }
  }
  return seq;
}

}  // namespace dala
