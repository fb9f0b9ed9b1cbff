#include "core/io/dataset.h"

#include <filesystem>
#include <sstream>

#include "core/error.h"
#include "core/io/euroc_dataset.h"
#include "core/io/image_sequence.h"
#include "core/io/kitti_dataset.h"
#include "core/io/synthetic_dataset.h"
#include "core/io/tum_dataset.h"

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
  }
  return "?";
}

DatasetFormat ParseDatasetFormat(const std::string& name) {
  for (DatasetFormat f : {DatasetFormat::kAuto, DatasetFormat::kKitti, DatasetFormat::kEuroc,
                          DatasetFormat::kTum, DatasetFormat::kSynthetic}) {
    if (name == DatasetFormatName(f)) return f;
  }
  throw Error() << "unknown dataset format '" << name
                << "': use one of auto, kitti, euroc, tum, synthetic";
}

bool DatasetOptions::IsValid(std::string* why) const {
  std::ostringstream os;
  if (first_frame < 0) {
    os << "first_frame " << first_frame << " must be >= 0";
  } else if (max_frames < 0) {
    os << "max_frames " << max_frames << " must be >= 0 (0 for all)";
  } else if (!(max_ground_truth_gap_s > 0)) {
    os << "max_ground_truth_gap_s " << max_ground_truth_gap_s << " must be > 0";
  }
  if (why != nullptr) *why = os.str();
  return os.str().empty();
}

DatasetFormat DetectDatasetFormat(const std::string& folder) {
  if (!fs::is_directory(folder)) {
    throw Error() << "missing dataset folder '" << folder << "': check the path";
  }
  const auto file = [&](const char* name) { return fs::is_regular_file(folder + "/" + name); };
  const auto dir = [&](const char* name) { return fs::is_directory(folder + "/" + name); };
  if (file(kSyntheticMarkerFile)) return DatasetFormat::kSynthetic;
  if (dir("image_0")) return DatasetFormat::kKitti;
  if (dir("mav0") || file("cam0/sensor.yaml")) return DatasetFormat::kEuroc;
  if (file("rgb.txt")) return DatasetFormat::kTum;
  throw Error() << "cannot tell the dataset format of '" << folder << "': looked for "
                << kSyntheticMarkerFile << " (synthetic), image_0/ (KITTI), mav0/ or "
                << "cam0/sensor.yaml (EuRoC), rgb.txt (TUM); point to the sequence folder "
                << "or set the format (--format)";
}

std::unique_ptr<Dataset> OpenDataset(const std::string& folder, const DatasetOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) throw Error() << "invalid dataset options: " << why;
  const DatasetFormat format =
      options.format == DatasetFormat::kAuto ? DetectDatasetFormat(folder) : options.format;
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
    case DatasetFormat::kAuto:
      break;
  }
  return MakeImageSequenceDataset(std::move(sequence), options);
}

}  // namespace dala
