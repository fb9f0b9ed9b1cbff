#ifndef DALA_CORE_IO_SYNTHETIC_DATASET_H_
#define DALA_CORE_IO_SYNTHETIC_DATASET_H_

// Sequences written by `dala synth`: the KITTI layout (core/io/kitti_dataset.h) plus a marker
// `synth.yaml` (cv::FileStorage) with at least format: "dala-synthetic", version: 1, preset, seed.

#include <string>

#include "core/io/dataset.h"
#include "core/io/image_sequence.h"

namespace dala {

inline constexpr const char* kSyntheticMarkerFile = "synth.yaml";
inline constexpr const char* kSyntheticFormatTag = "dala-synthetic";
inline constexpr int kSyntheticFormatVersion = 1;

// Checks the marker, then reads the folder with the KITTI reader. Throws dala::Error on a marker
// with another format tag or version, or a malformed folder.
ImageSequence ReadSyntheticSequence(const std::string& folder, const DatasetOptions& options);

}  // namespace dala

#endif  // DALA_CORE_IO_SYNTHETIC_DATASET_H_
