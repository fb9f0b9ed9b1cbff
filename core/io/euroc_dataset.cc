#include "core/io/euroc_dataset.h"

#include <glog/logging.h>

#include <filesystem>
#include <map>

#include "core/config.h"
#include "core/io/camera_calibration.h"
#include "core/error.h"
#include "core/io/text_lines.h"
#include "core/io/trajectory_io.h"

namespace dala {
namespace fs = std::filesystem;
namespace {

struct CsvImage {
  int64_t t_ns = 0;
  std::string file;
  std::string where;  // "<data.csv>:<line>", for messages.
};

std::vector<CsvImage> ReadImageCsv(const std::string& cam_dir) {
  const std::string csv = cam_dir + "/data.csv";
  RequireFile(csv, "the image list 't_ns,filename'");
  std::vector<CsvImage> images;
  for (const NumberedLine& line : ReadDataLines(csv, "the EuRoC image list")) {
    const std::vector<std::string> fields = SplitFields(line.text);
    if (fields.size() != 2) {
      throw Error() << csv << ":" << line.number << ": expected 2 fields 't_ns,filename', got "
                    << fields.size();
    }
    CsvImage image;
    size_t used = 0;
    try {
      image.t_ns = std::stoll(fields[0], &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used == 0 || used != fields[0].size()) {
      throw Error() << csv << ":" << line.number << ": '" << fields[0]
                    << "' is not a timestamp in integer nanoseconds";
    }
    if (!images.empty() && image.t_ns <= images.back().t_ns) {
      throw Error() << csv << ":" << line.number << ": timestamp " << image.t_ns
                    << " does not increase (previous " << images.back().t_ns
                    << "); sort the file by time";
    }
    image.file = cam_dir + "/data/" + fields[1];  // Checked for the frames to run (below).
    image.where = csv + ":" + std::to_string(line.number);
    images.push_back(std::move(image));
  }
  if (images.empty()) throw Error() << csv << ": lists no image";
  return images;
}

RawCamera RawCameraOf(const PinholeCamera& c) {
  RawCamera raw;
  raw.width = c.width;
  raw.height = c.height;
  raw.fx = c.fx;
  raw.fy = c.fy;
  raw.cx = c.cx;
  raw.cy = c.cy;
  raw.distortion = c.distortion;
  return raw;
}

std::vector<double> RequireNumbers(const ConfigNode& node, const char* key, size_t min_size,
                                   size_t max_size) {
  std::vector<double> v;
  if (!node.Has(key)) throw Error() << node.Where(key) << ": missing";
  node.Read(key, &v);
  if (v.size() < min_size || v.size() > max_size) {
    throw Error() << node.Where(key) << ": has " << v.size() << " numbers, expected "
                  << (min_size == max_size
                          ? std::to_string(min_size)
                          : std::to_string(min_size) + " to " + std::to_string(max_size));
  }
  return v;
}

}  // namespace

EurocCamera ReadEurocSensorYaml(const std::string& path) {
  RequireFile(path, "the EuRoC camera calibration");
  const ConfigNode root = LoadConfigFile(path);
  std::string model = "pinhole", distortion_model = "radial-tangential";
  root.Read("camera_model", &model);
  root.Read("distortion_model", &distortion_model);
  if (model != "pinhole") {
    throw Error() << path << ": camera_model '" << model << "' is not supported (pinhole only)";
  }
  if (distortion_model != "radial-tangential" && distortion_model != "radtan") {
    throw Error() << path << ": distortion_model '" << distortion_model
                  << "' is not supported (radial-tangential only)";
  }
  EurocCamera out;
  PinholeCamera& cam = out.camera;
  const auto intrinsics = RequireNumbers(root, "intrinsics", 4, 4);
  cam.fx = intrinsics[0];
  cam.fy = intrinsics[1];
  cam.cx = intrinsics[2];
  cam.cy = intrinsics[3];
  const auto distortion = RequireNumbers(root, "distortion_coefficients", 4, 5);
  for (size_t i = 0; i < distortion.size(); ++i) cam.distortion[i] = distortion[i];
  const auto resolution = RequireNumbers(root, "resolution", 2, 2);
  cam.width = static_cast<int>(resolution[0]);
  cam.height = static_cast<int>(resolution[1]);
  const auto T = RequireNumbers(root.Child("T_BS"), "data", 16, 16);
  Eigen::Matrix4d M;
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) M(r, c) = T[4 * r + c];
  }
  const Eigen::Matrix3d R = M.topLeftCorner<3, 3>();
  if ((R.transpose() * R - Eigen::Matrix3d::Identity()).norm() > 1e-3 || R.determinant() < 0) {
    throw Error() << path << ": T_BS's 3x3 block is not a rotation";
  }
  out.T_b_c = Orthonormalized(MakePose(R, M.topRightCorner<3, 1>()));
  std::string why;
  if (!cam.IsValid(&why)) throw Error() << path << ": invalid camera: " << why;
  return out;
}

ImageSequence ReadEurocSequence(const std::string& folder, const DatasetOptions& options) {
  RequireFolder(folder, "the EuRoC sequence folder");
  if (!options.calibration_yaml.empty()) {
    throw Error() << "calibration_yaml '" << options.calibration_yaml << "' cannot be used with "
                  << "EuRoC: the reader rectifies with the sensor.yaml files; drop the option";
  }
  const std::string mav0 = fs::is_directory(folder + "/mav0") ? folder + "/mav0" : folder;
  const std::string cam0_dir = mav0 + "/cam0", cam1_dir = mav0 + "/cam1";
  RequireFolder(cam0_dir, "the left camera, mav0/cam0");
  const bool stereo = fs::is_directory(cam1_dir) && !options.force_mono;

  const EurocCamera cam0 = ReadEurocSensorYaml(cam0_dir + "/sensor.yaml");
  const std::vector<CsvImage> images0 = ReadImageCsv(cam0_dir);

  ImageSequence seq;
  std::vector<std::string> left_where, right_where;  // Per frame, the data.csv lines.
  seq.format = DatasetFormat::kEuroc;
  seq.path = folder;
  seq.raw_size = cv::Size(cam0.camera.width, cam0.camera.height);
  seq.raw_size_source = cam0_dir + "/sensor.yaml resolution";
  Pose T_c0_c0rect = Pose::Identity();

  if (stereo) {
    const EurocCamera cam1 = ReadEurocSensorYaml(cam1_dir + "/sensor.yaml");
    if (cam1.camera.width != cam0.camera.width || cam1.camera.height != cam0.camera.height) {
      throw Error() << cam1_dir << "/sensor.yaml: resolution " << cam1.camera.width << "x"
                    << cam1.camera.height << " differs from cam0's " << cam0.camera.width << "x"
                    << cam0.camera.height;
    }
    std::map<int64_t, CsvImage> right_by_time;
    for (CsvImage& image : ReadImageCsv(cam1_dir)) right_by_time[image.t_ns] = std::move(image);
    size_t unpaired = 0;
    for (const CsvImage& image : images0) {
      const auto it = right_by_time.find(image.t_ns);
      if (it == right_by_time.end()) {
        ++unpaired;
        continue;
      }
      seq.t_ns.push_back(image.t_ns);
      seq.left_files.push_back(image.file);
      left_where.push_back(image.where);
      seq.right_files.push_back(it->second.file);
      right_where.push_back(it->second.where);
    }
    if (unpaired > 0) {
      LOG(WARNING) << cam0_dir << ": " << unpaired << " of " << images0.size()
                   << " images have no cam1 image with the same timestamp; skipped";
    }
    if (seq.t_ns.empty()) {
      throw Error() << mav0 << ": no cam0 image has a cam1 image with the same timestamp; "
                    << "read the sequence as monocular (force_mono / --mode mono)";
    }

    // OpenCV's stereo extrinsics map cam0 to cam1: p_c1 = R p_c0 + T, i.e. T_c1_c0. The pair is
    // rectified as every raw pair is (MakeRectification: cv::stereoRectify, alpha 0).
    CameraCalibration calibration;
    calibration.path = cam0_dir + "/sensor.yaml";
    calibration.cam0 = RawCameraOf(cam0.camera);
    calibration.cam1 = RawCameraOf(cam1.camera);
    calibration.T_c1_c0 = cam1.T_b_c.inverse() * cam0.T_b_c;
    Rectification rect;
    try {
      rect = MakeRectification(calibration, /*stereo=*/true);
    } catch (const Error& e) {
      // (The sizes and lens models match: what fails is the right camera's side.)
      throw Error() << mav0 << ": cam1 is not to the right of cam0 after rectification: check "
                    << "T_BS in the sensor.yaml files (" << e.message() << ")";
    }
    seq.rig = rect.rig;
    seq.left_map1 = rect.left_map1;
    seq.left_map2 = rect.left_map2;
    seq.right_map1 = rect.right_map1;
    seq.right_map2 = rect.right_map2;
    T_c0_c0rect = rect.T_c0_c0rect;
  } else {
    for (const CsvImage& image : images0) {
      seq.t_ns.push_back(image.t_ns);
      seq.left_files.push_back(image.file);
      left_where.push_back(image.where);
    }
    seq.rig.left = MakeUndistortionMaps(cam0.camera, &seq.left_map1, &seq.left_map2);
  }
  const FrameRange range = SelectFrames(seq.t_ns.size(), options, folder);
  std::vector<MissingImage> missing;
  for (size_t i = range.begin; i < range.end; ++i) {
    std::string message;
    if (!fs::is_regular_file(seq.left_files[i])) {
      message = left_where[i] + ": missing image '" + seq.left_files[i] + "'";
    } else if (stereo && !fs::is_regular_file(seq.right_files[i])) {
      message = right_where[i] + ": missing image '" + seq.right_files[i] + "'";
    }
    if (!message.empty()) missing.push_back({i, message + ": restore it or remove the line"});
  }
  CheckMissingImages(missing, range, options, folder);
  // Fail early on a first image of the wrong size.
  LoadGrayImage(seq.left_files[range.begin], seq.raw_size, seq.raw_size_source);

  const std::string gt_path = mav0 + "/state_groundtruth_estimate0/data.csv";
  if (fs::is_regular_file(gt_path)) {
    const Trajectory T_w_b = ReadTrajectory(gt_path, TrajectoryFormat::kEurocCsv);
    const Pose T_b_c0rect = cam0.T_b_c * T_c0_c0rect;
    seq.T_w_c0_gt =
        GroundTruthAtTimes(T_w_b, seq.t_ns, NsFromSeconds(options.max_ground_truth_gap_s));
    for (auto& T : seq.T_w_c0_gt) {
      if (T) T = *T * T_b_c0rect;
    }
  }
  return seq;
}

}  // namespace dala
