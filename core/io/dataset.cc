#include "core/io/dataset.h"

#include <cmath>
#include <filesystem>
#include <sstream>

#include "core/error.h"
#include "core/io/bag_dataset.h"
#include "core/io/euroc_dataset.h"
#include "core/io/image_folder_dataset.h"
#include "core/io/image_sequence.h"
#include "core/io/kitti_dataset.h"
#include "core/io/synthetic_dataset.h"
#include "core/io/tum_dataset.h"
#include "core/io/video_dataset.h"

namespace dala {
namespace fs = std::filesystem;

const char* DatasetFormatName(DatasetFormat format) {
  switch (format) {
    case DatasetFormat::kAuto:
      return "auto";
    case DatasetFormat::kKitti:
      return "kitti";
    case DatasetFormat::kEuroc:
      return "euroc";
    case DatasetFormat::kTum:
      return "tum";
    case DatasetFormat::kSynthetic:
      return "synthetic";
    case DatasetFormat::kImages:
      return "images";
    case DatasetFormat::kVideo:
      return "video";
    case DatasetFormat::kBag:
      return "bag";
  }
  return "?";
}

DatasetFormat ParseDatasetFormat(const std::string& name) {
  for (DatasetFormat f : {DatasetFormat::kAuto, DatasetFormat::kKitti, DatasetFormat::kEuroc,
                          DatasetFormat::kTum, DatasetFormat::kSynthetic, DatasetFormat::kImages,
                          DatasetFormat::kVideo, DatasetFormat::kBag}) {
    if (name == DatasetFormatName(f)) return f;
  }
  throw Error() << "unknown dataset format '" << name
                << "': use one of auto, kitti, euroc, tum, synthetic, images, video, bag";
}

bool DatasetOptions::IsValid(std::string* why) const {
  std::ostringstream os;
  if (first_frame < 0) {
    os << "first_frame " << first_frame << " must be >= 0";
  } else if (max_frames < 0) {
    os << "max_frames " << max_frames << " must be >= 0 (0 for all)";
  } else if (!(max_ground_truth_gap_s > 0)) {
    os << "max_ground_truth_gap_s " << max_ground_truth_gap_s << " must be > 0";
  } else if (!(fps >= 0) || !std::isfinite(fps)) {
    os << "fps " << fps << " must be > 0 (0: times from the source)";
  } else if (stereo_layout != "mono" && stereo_layout != "side_by_side") {
    os << "stereo_layout '" << stereo_layout << "' must be mono or side_by_side";
  }
  if (why != nullptr) *why = os.str();
  return os.str().empty();
}

DatasetFormat DetectDatasetFormat(const std::string& folder) {
  if (fs::is_regular_file(folder)) {
    return fs::path(folder).extension() == ".bag" ? DatasetFormat::kBag : DatasetFormat::kVideo;
  }
  if (!fs::is_directory(folder)) {
    throw Error() << "missing dataset folder or video '" << folder << "': check the path";
  }
  const auto file = [&](const char* name) { return fs::is_regular_file(folder + "/" + name); };
  const auto dir = [&](const char* name) { return fs::is_directory(folder + "/" + name); };
  if (file(kSyntheticMarkerFile)) return DatasetFormat::kSynthetic;
  if (dir("image_0")) return DatasetFormat::kKitti;
  if (dir("mav0") || file("cam0/sensor.yaml")) return DatasetFormat::kEuroc;
  if (file("rgb.txt")) return DatasetFormat::kTum;
  if (!ListImageFiles(folder).empty()) return DatasetFormat::kImages;
  throw Error() << "cannot tell the dataset format of '" << folder << "': looked for "
                << kSyntheticMarkerFile << " (synthetic), image_0/ (KITTI), mav0/ or "
                << "cam0/sensor.yaml (EuRoC), rgb.txt (TUM), png/jpg images (a folder of "
                << "images with --calibration); point to the sequence folder, a video file "
                << "or set the format (--format)";
}

std::unique_ptr<Dataset> OpenDataset(const std::string& folder, const DatasetOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) throw Error() << "invalid dataset options: " << why;
  const DatasetFormat format =
      options.format == DatasetFormat::kAuto ? DetectDatasetFormat(folder) : options.format;
  const bool images = format == DatasetFormat::kImages, bag = format == DatasetFormat::kBag;
  const bool video = format == DatasetFormat::kVideo;
  const auto refuse = [&](bool used, const char* option, const char* applies_to) {
    if (used) {
      throw Error() << "option " << option << " applies to " << applies_to << ", not to the "
                    << DatasetFormatName(format) << " dataset '" << folder << "': drop it";
    }
  };
  refuse(!images && !options.right_folder.empty(), "right_folder (--right_folder)",
         "image folders");
  refuse(!images && !options.times_file.empty(), "times_file (--times)", "image folders");
  refuse(!images && !video && options.fps > 0, "fps (--fps)", "image folders and videos");
  refuse(!video && options.stereo_layout != "mono", "stereo_layout (--stereo_layout)", "videos");
  refuse(!images && !video && !bag && !options.ground_truth.empty(),
         "ground_truth (--ground_truth)",
         "image folders, videos and bags (the datasets bring their own)");
  refuse(!bag && !options.topic.empty(), "topic (--topic)", "bags");
  refuse(!bag && !options.right_topic.empty(), "right_topic (--right_topic)", "bags");
  ImageSequence sequence;
  switch (format) {
    case DatasetFormat::kKitti:
      sequence = ReadKittiSequence(folder, options);
      break;
    case DatasetFormat::kSynthetic:
      sequence = ReadSyntheticSequence(folder, options);
      break;
    case DatasetFormat::kEuroc:
      sequence = ReadEurocSequence(folder, options);
      break;
    case DatasetFormat::kTum:
      sequence = ReadTumSequence(folder, options);
      break;
    case DatasetFormat::kImages:
      sequence = ReadImageFolderSequence(folder, options);
      break;
    case DatasetFormat::kVideo:
      return OpenVideoDataset(folder, options);
    case DatasetFormat::kBag:
      return OpenBagDataset(folder, options);
    case DatasetFormat::kAuto:
      break;
  }
  return MakeImageSequenceDataset(std::move(sequence), options);
}

}  // namespace dala
