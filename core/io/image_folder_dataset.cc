#include "core/io/image_folder_dataset.h"

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <map>

#include "core/error.h"
#include "core/io/camera_calibration.h"
#include "core/io/trajectory_io.h"

namespace dala {
namespace fs = std::filesystem;
namespace {

bool IsImageFile(const fs::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  for (const char* e : {".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff", ".pgm", ".ppm"}) {
    if (ext == e) return true;
  }
  return false;
}

// A file name stem that is a non-negative decimal number: digits, at most one '.'.
bool IsNumber(const std::string& stem) {
  if (stem.empty() || stem.front() == '.' || stem.back() == '.') return false;
  int dots = 0;
  for (char c : stem) {
    if (c == '.') {
      ++dots;
    } else if (!std::isdigit(static_cast<unsigned char>(c))) {
      return false;
    }
  }
  return dots <= 1;
}

std::string Stem(const std::string& file) { return fs::path(file).stem().string(); }

// Times from numeric file names; empty when the names do not carry times.
std::vector<int64_t> TimesFromNames(const std::vector<std::string>& files) {
  std::vector<int64_t> t;
  for (const std::string& f : files) {
    const std::string stem = Stem(f);
    if (!IsNumber(stem)) return {};
    if (stem.find('.') != std::string::npos) {
      t.push_back(NsFromSeconds(std::stod(stem)));
    } else if (stem.size() >= 16) {
      t.push_back(std::stoll(stem));
    } else {
      return {};  // Frame numbers, not times.
    }
  }
  return t;
}

}  // namespace

std::vector<std::string> ListImageFiles(const std::string& folder) {
  std::vector<std::string> files;
  for (const auto& entry : fs::directory_iterator(folder)) {
    if (entry.is_regular_file() && IsImageFile(entry.path())) files.push_back(entry.path().string());
  }
  bool numeric = !files.empty();
  for (const std::string& f : files) numeric = numeric && IsNumber(Stem(f));
  if (numeric) {
    std::sort(files.begin(), files.end(), [](const std::string& a, const std::string& b) {
      const std::string sa = Stem(a), sb = Stem(b);
      const double da = std::stod(sa), db = std::stod(sb);
      return da != db ? da < db : sa < sb;
    });
  } else {
    std::sort(files.begin(), files.end());
  }
  return files;
}

ImageSequence ReadImageFolderSequence(const std::string& folder, const DatasetOptions& options) {
  RequireFolder(folder, "the image folder");
  ImageSequence seq;
  seq.format = DatasetFormat::kImages;
  seq.path = folder;
  seq.left_files = ListImageFiles(folder);
  if (seq.left_files.empty()) {
    throw Error() << folder << ": holds no image (png, jpg, jpeg, bmp, tif, pgm, ppm)";
  }
  if (options.calibration_yaml.empty()) {
    throw Error() << folder << ": a folder of images needs its camera calibration: give "
                  << "--calibration FILE (OpenCV, ROS camera_info, Kalibr or dala YAML; "
                  << "`dala calibrate` writes one; docs/datasets.md, \"Your own camera\")";
  }
  const size_t n = seq.left_files.size();
  const bool stereo = !options.right_folder.empty() && !options.force_mono;
  if (stereo) {
    RequireFolder(options.right_folder, "the right camera's images (--right_folder)");
    const std::vector<std::string> right = ListImageFiles(options.right_folder);
    std::map<std::string, std::string> right_by_name;
    for (const std::string& f : right) right_by_name[fs::path(f).filename().string()] = f;
    bool by_name = true;
    for (const std::string& f : seq.left_files) {
      by_name = by_name && right_by_name.count(fs::path(f).filename().string()) > 0;
    }
    if (by_name) {
      for (const std::string& f : seq.left_files) {
        seq.right_files.push_back(right_by_name[fs::path(f).filename().string()]);
      }
    } else if (right.size() == n) {
      seq.right_files = right;
    } else {
      throw Error() << options.right_folder << ": holds " << right.size() << " images for the "
                    << n << " of " << folder << ", and not under the same names: give the "
                    << "right folder one image per left image (same name, or same order)";
    }
  }

  // Times.
  std::string times_path = options.times_file;
  if (times_path.empty() && fs::is_regular_file(folder + "/times.txt")) {
    times_path = folder + "/times.txt";
  }
  if (options.fps > 0) {
    for (size_t i = 0; i < n; ++i) {
      seq.t_ns.push_back(NsFromSeconds(static_cast<double>(i) / options.fps));
    }
  } else if (!times_path.empty()) {
    seq.t_ns = ReadTimesFile(times_path);
    if (seq.t_ns.size() != n) {
      throw Error() << times_path << " has " << seq.t_ns.size() << " times for the " << n
                    << " images of " << folder << ": give one time (seconds) per image";
    }
  } else {
    seq.t_ns = TimesFromNames(seq.left_files);
    if (seq.t_ns.empty()) {
      throw Error() << folder << ": the image names (e.g. '"
                    << fs::path(seq.left_files.front()).filename().string()
                    << "') carry no times: give the frame rate (--fps), a times file (--times, "
                    << "seconds, one line per image), or name the images by time (seconds "
                    << "with a decimal point, or integer nanoseconds)";
    }
  }
  for (size_t i = 1; i < n; ++i) {
    if (seq.t_ns[i] <= seq.t_ns[i - 1]) {
      throw Error() << folder << ": the time of image '" << seq.left_files[i]
                    << "' does not increase (" << SecondsFromNs(seq.t_ns[i]) << " s after "
                    << SecondsFromNs(seq.t_ns[i - 1]) << " s)";
    }
  }

  const FrameRange range = SelectFrames(n, options, folder);
  const Pose T_c0_c0rect =
      ApplyCalibration(ReadCameraCalibration(options.calibration_yaml), stereo, &seq);
  LoadGrayImage(seq.left_files[range.begin], seq.raw_size, seq.raw_size_source);
  if (stereo) LoadGrayImage(seq.right_files[range.begin], seq.raw_size, seq.raw_size_source);
  if (!options.ground_truth.empty()) {
    seq.T_w_c0_gt = ReadGroundTruthFile(options.ground_truth, seq.t_ns, options, T_c0_c0rect);
  }
  return seq;
}

}  // namespace dala
