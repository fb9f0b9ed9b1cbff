#include "core/io/tum_dataset.h"

#include <filesystem>

#include "core/error.h"
#include "core/io/camera_calibration.h"
#include "core/io/text_lines.h"
#include "core/io/trajectory_io.h"

namespace dala {
namespace fs = std::filesystem;

std::optional<PinholeCamera> TumIntrinsicsForSequence(const std::string& name) {
  const auto has = [&](const char* s) { return name.find(s) != std::string::npos; };
  PinholeCamera cam;
  cam.width = 640;
  cam.height = 480;
  if (has("freiburg1") || has("fr1")) {
    cam.fx = 517.3, cam.fy = 516.5, cam.cx = 318.6, cam.cy = 255.3;
    cam.distortion << 0.2624, -0.9531, -0.0054, 0.0026, 1.1633;
  } else if (has("freiburg2") || has("fr2")) {
    cam.fx = 520.9, cam.fy = 521.0, cam.cx = 325.1, cam.cy = 249.7;
    cam.distortion << 0.2312, -0.7849, -0.0033, -0.0001, 0.9172;
  } else if (has("freiburg3") || has("fr3")) {
    cam.fx = 535.4, cam.fy = 539.2, cam.cx = 320.1, cam.cy = 247.6;
  } else {
    return std::nullopt;
  }
  return cam;
}

ImageSequence ReadTumSequence(const std::string& folder, const DatasetOptions& options) {
  RequireFolder(folder, "the TUM sequence folder");
  const std::string list = folder + "/rgb.txt";
  RequireFile(list, "the image list 't filename'");

  ImageSequence seq;
  std::vector<int> line_of;  // Per frame, its line in rgb.txt (for messages).
  seq.format = DatasetFormat::kTum;
  seq.path = folder;
  for (const NumberedLine& line : ReadDataLines(list, "the TUM image list")) {
    const std::vector<std::string> fields = SplitFields(line.text);
    if (fields.size() != 2) {
      throw Error() << list << ":" << line.number << ": expected 't filename', got "
                    << fields.size() << " fields";
    }
    const int64_t t_ns = ParseSecondsAsNs(list, line.number, fields[0]);
    if (!seq.t_ns.empty() && t_ns <= seq.t_ns.back()) {
      throw Error() << list << ":" << line.number << ": time " << fields[0]
                    << " does not increase; sort the file by time";
    }
    seq.t_ns.push_back(t_ns);
    seq.left_files.push_back(folder + "/" + fields[1]);
    line_of.push_back(line.number);
  }
  if (seq.t_ns.empty()) throw Error() << list << ": lists no image";
  const FrameRange range = SelectFrames(seq.t_ns.size(), options, folder);
  std::vector<MissingImage> missing;
  for (size_t i = range.begin; i < range.end; ++i) {
    if (fs::is_regular_file(seq.left_files[i])) continue;
    missing.push_back({i, list + ":" + std::to_string(line_of[i]) + ": missing image '" +
                              seq.left_files[i] + "': restore it or remove the line"});
  }
  CheckMissingImages(missing, range, options, folder);

  if (!options.calibration_yaml.empty()) {
    ApplyCalibration(ReadCameraCalibration(options.calibration_yaml), /*stereo=*/false, &seq);
  } else {
    const std::string name = fs::weakly_canonical(fs::path(folder)).filename().string();
    const auto cam = TumIntrinsicsForSequence(name);
    if (!cam) {
      throw Error() << folder << ": cannot tell the TUM camera from the folder name '" << name
                    << "' (expected freiburg1/2/3 or fr1/2/3 in it); give the intrinsics in a "
                    << "calibration file (--calibration)";
    }
    const PinholeCamera& raw = *cam;
    seq.raw_size_source = "the TUM " + name + " camera (640x480)";
    seq.raw_size = cv::Size(raw.width, raw.height);
    seq.rig.left =
        raw.HasDistortion() ? MakeUndistortionMaps(raw, &seq.left_map1, &seq.left_map2) : raw;
  }
  LoadGrayImage(seq.left_files[range.begin], seq.raw_size, seq.raw_size_source);

  const std::string gt_path = folder + "/groundtruth.txt";
  if (fs::is_regular_file(gt_path)) {
    seq.T_w_c0_gt = GroundTruthAtTimes(ReadTrajectory(gt_path, TrajectoryFormat::kTum), seq.t_ns,
                                       NsFromSeconds(options.max_ground_truth_gap_s));
  }
  return seq;
}

}  // namespace dala
