#include "core/io/synthetic_dataset.h"

#include "core/config.h"
#include "core/error.h"
#include "core/io/kitti_dataset.h"

namespace dala {

ImageSequence ReadSyntheticSequence(const std::string& folder, const DatasetOptions& options) {
  RequireFolder(folder, "the synthetic sequence folder");
  const std::string marker = folder + "/" + kSyntheticMarkerFile;
  RequireFile(marker, "the marker written by `dala synth`");
  // The marker holds more keys (the generator's options); only the format is checked here.
  const ConfigNode root = LoadConfigFile(marker);
  std::string tag;
  int version = -1;
  root.Read("format", &tag);
  root.Read("version", &version);
  if (tag != kSyntheticFormatTag) {
    throw Error() << marker << ": format is '" << tag << "', expected '" << kSyntheticFormatTag
                  << "' (is this folder written by `dala synth`?)";
  }
  if (version != kSyntheticFormatVersion) {
    throw Error() << marker << ": version " << version << " is not supported (this dala reads "
                  << "version " << kSyntheticFormatVersion << "); regenerate with `dala synth`";
  }
  // Rendered through a lens: the calibration with the lens (calib.txt has the raw K only).
  std::string lens = "pinhole";
  root.Read("lens", &lens);
  if (lens != "pinhole" && options.calibration_yaml.empty()) {
    DatasetOptions with_lens = options;
    with_lens.calibration_yaml = folder + "/calibration/kalibr.yaml";
    RequireFile(with_lens.calibration_yaml, "the calibration of the lens the images have");
    return ReadKittiSequence(folder, with_lens, DatasetFormat::kSynthetic);
  }
  return ReadKittiSequence(folder, options, DatasetFormat::kSynthetic);
}

}  // namespace dala
