#ifndef DALA_CORE_IO_VIDEO_DATASET_H_
#define DALA_CORE_IO_VIDEO_DATASET_H_

// A video file (any container and codec OpenCV's FFmpeg video I/O opens: mp4, mkv, avi, mov, ...)
// with a calibration file (DatasetOptions::calibration_yaml, required):
//   - frames: decoded in order; DatasetOptions::first_frame / max_frames select them;
//   - times: the container's presentation times (CAP_PROP_POS_MSEC), or frame i at i / fps with
//     DatasetOptions::fps (also when the container's times do not increase);
//   - stereo: DatasetOptions::stereo_layout "side_by_side": the left half of each frame is the
//     left camera, the right half the right one (the calibration describes one half);
//   - colour frames are converted to grayscale, then undistorted / rectified (MakeRectification);
//   - ground truth: DatasetOptions::ground_truth (TUM by time, KITTI by frame index).
// Opening indexes the frames to run once (a decoding pass without conversion), so that size()
// and the times are exact; Rewind() reopens the file.

#include <memory>
#include <string>

#include "core/io/dataset.h"

namespace dala {

// Throws dala::Error naming the file and the fix: a missing or empty file, a file FFmpeg cannot
// open (not a video, or a container it does not know), a video whose codec cannot be decoded
// (the first frame cannot be read), a calibration of another frame size, no times.
std::unique_ptr<Dataset> OpenVideoDataset(const std::string& path, const DatasetOptions& options);

}  // namespace dala

#endif  // DALA_CORE_IO_VIDEO_DATASET_H_
