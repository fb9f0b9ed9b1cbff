#ifndef DALA_CORE_IO_IMAGE_SEQUENCE_H_
#define DALA_CORE_IO_IMAGE_SEQUENCE_H_

// The common form each dataset reader reduces a folder to, the Dataset that plays it, and the
// helpers the readers share (image loading with checks, ground-truth interpolation, undistortion).
// Internal to core/io: the public entry point is OpenDataset (core/io/dataset.h).

#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "core/camera.h"
#include "core/io/camera_calibration.h"
#include "core/io/dataset.h"
#include "core/trajectory.h"

namespace dala {

struct ImageSequence {
  DatasetFormat format = DatasetFormat::kAuto;
  std::string path;
  StereoRig rig;      // Of the images Next() yields (after remapping): no distortion.
  cv::Size raw_size;  // Size of every image file on disk.
  std::string
      raw_size_source;  // What fixed raw_size, for messages ("calib.txt", "the first image").
  std::vector<int64_t> t_ns;
  std::vector<std::string> left_files;
  std::vector<std::string> right_files;        // Empty when monocular.
  std::vector<std::optional<Pose>> T_w_c0_gt;  // One per frame, or empty without ground truth.
  std::vector<Pose> T_w_odom;  // Odometry (Frame::T_w_odom): one per frame, or empty without.
  // Remap tables (cv::remap) from the raw to the rectified/undistorted images; empty: none.
  cv::Mat left_map1, left_map2, right_map1, right_map2;
};

// The frames [begin, end) that options.first_frame / max_frames select of a sequence of n frames.
// Throws dala::Error naming `path` when there is no frame or first_frame is past the end.
struct FrameRange {
  size_t begin = 0;
  size_t end = 0;
};
FrameRange SelectFrames(size_t n, const DatasetOptions& options, const std::string& path);

// An image file the index names for a selected frame, absent from the folder (one per frame).
struct MissingImage {
  size_t frame = 0;
  std::string message;  // Names the file and the fix, as an error would.
};
// Refuses the missing images (dala::Error with the first message) unless
// options.allow_missing_images, which logs one warning instead (their frames are skipped when
// read: Next() throws FrameError). A missing image of the range's first frame is refused either
// way: that frame fixes the image size and the world frame.
void CheckMissingImages(const std::vector<MissingImage>& missing, const FrameRange& range,
                        const DatasetOptions& options, const std::string& path);

// Plays a sequence, honouring options.first_frame / max_frames. Throws dala::Error when
// first_frame is past the end.
std::unique_ptr<Dataset> MakeImageSequenceDataset(ImageSequence sequence,
                                                  const DatasetOptions& options);

// Reads an image as 8-bit grayscale. Throws dala::Error when it cannot be read (missing, corrupt,
// not an image) or when `expected` is non-empty and the size differs (naming `expected_source`).
cv::Mat LoadGrayImage(const std::string& path, const cv::Size& expected,
                      const std::string& expected_source);

// Throw dala::Error naming `what` and the fix when the folder / file is absent.
void RequireFolder(const std::string& path, const std::string& what);
void RequireFile(const std::string& path, const std::string& what);

// Ground truth at each time by InterpolatePose between the two samples around it, when they are
// at most max_gap_ns apart; a time outside the ground truth's range (beyond a 1 ms tolerance for
// rounded stamps) or in a larger gap gets nullopt.
std::vector<std::optional<Pose>> GroundTruthAtTimes(const Trajectory& ground_truth,
                                                    const std::vector<int64_t>& t_ns,
                                                    int64_t max_gap_ns);

// Maps that undistort `camera` into a distortion-free camera of the same size (returned), with
// cv::getOptimalNewCameraMatrix(alpha = 0: only valid pixels, no black border).
PinholeCamera MakeUndistortionMaps(const PinholeCamera& camera, cv::Mat* map1, cv::Mat* map2);

// A user's ground truth file (DatasetOptions::ground_truth) of the raw left camera, at the
// frame times t_ns: TUM (or EuRoC csv) by time (GroundTruthAtTimes), KITTI by frame index (it
// needs at least as many rows as frames). Each pose is returned as T_w_c0 * T_c0_c0rect.
// Throws dala::Error naming the file.
std::vector<std::optional<Pose>> ReadGroundTruthFile(const std::string& path,
                                                     const std::vector<int64_t>& t_ns,
                                                     const DatasetOptions& options,
                                                     const Pose& T_c0_c0rect);

// Applies a calibration file (--calibration, any format ReadCameraCalibration reads) to a
// sequence of raw images: sets seq->rig, the remap tables (MakeRectification), raw_size and
// raw_size_source (the file). Returns T_c0_c0rect (ground truth of the raw left camera T_w_c0
// becomes T_w_c0 * T_c0_c0rect). Throws dala::Error when the images are stereo and the
// calibration describes one camera.
Pose ApplyCalibration(const CameraCalibration& calibration, bool stereo, ImageSequence* seq);

}  // namespace dala

#endif  // DALA_CORE_IO_IMAGE_SEQUENCE_H_
