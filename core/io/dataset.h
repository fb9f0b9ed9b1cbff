#ifndef DALA_CORE_IO_DATASET_H_
#define DALA_CORE_IO_DATASET_H_

// Reading image sequences: KITTI odometry, EuRoC ASL, TUM RGB-D and the synthetic sequences
// `dala synth` writes. docs/datasets.md describes the folder layouts, the frames of the ground
// truth and the calibration override.
//
// Every reader hands out the same thing: rectified (stereo) or undistorted (mono) grayscale
// frames, a distortion-free StereoRig describing them, and the ground truth of the left rectified
// camera T_w_c0 at the frame times when the dataset has one.
//
//   std::unique_ptr<Dataset> dataset = OpenDataset("/data/kitti/sequences/06");
//   Frame frame;
//   while (dataset->Next(&frame)) { ... }
//
// Errors in the folder (missing or malformed files, wrong image sizes, unreadable images) throw
// dala::Error naming the file (and line) and the fix. An image that cannot be used is found when
// its frame is read: Next() throws FrameError, after which the caller may go on with the next
// frame (`dala run` skips the frame unless --strict). Not thread-safe.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include "core/camera.h"
#include "core/error.h"
#include "core/trajectory.h"
#include "core/types.h"

namespace dala {

// kImages: a plain folder of images with a calibration file (core/io/image_folder_dataset.h);
// kVideo: a video file (core/io/video_dataset.h); kBag: a ROS 1 bag (core/io/bag_dataset.h).
enum class DatasetFormat { kAuto, kKitti, kEuroc, kTum, kSynthetic, kImages, kVideo, kBag };

const char* DatasetFormatName(DatasetFormat format);
// Parses "auto", "kitti", "euroc", "tum", "synthetic", "images", "video", "bag"; throws dala::Error naming the accepted
// values.
DatasetFormat ParseDatasetFormat(const std::string& name);

// Thrown by Dataset::Next for a frame whose image cannot be used (missing, undecodable, of the
// wrong size). Next has moved past that frame: calling it again yields the frame after it.
class FrameError : public Error {
 public:
  FrameError(FrameId frame, int64_t t_ns, const std::string& message)
      : Error(message), frame_(frame), t_ns_(t_ns) {}
  FrameId frame() const { return frame_; }
  int64_t t_ns() const { return t_ns_; }

 private:
  FrameId frame_;
  int64_t t_ns_ = 0;
};

// A sequence of frames, yielded in time order.
class Dataset {
 public:
  virtual ~Dataset() = default;
  virtual DatasetFormat format() const = 0;
  virtual const std::string& path() const = 0;
  virtual bool is_stereo() const = 0;
  // The rectified rig the frames are expressed in (no distortion); mono: baseline 0.
  virtual const StereoRig& rig() const = 0;
  // Number of frames Next() yields from a Rewind().
  virtual size_t size() const = 0;
  // Loads the next frame; false at the end. Frame ids are the frame's index in the whole
  // sequence (so with DatasetOptions::first_frame = 10 the first id is 10). Throws FrameError
  // on a missing or unreadable image or one of the wrong size.
  virtual bool Next(Frame* frame) = 0;
  virtual void Rewind() = 0;
  // Ground truth T_w_c0 (the rectified left camera in the dataset's world frame) at the times of
  // the frames that have one (a subset, in order), when the dataset has ground truth.
  virtual const std::optional<Trajectory>& ground_truth() const = 0;
};

struct DatasetOptions {
  // kAuto detects the format from the folder content (see DetectDatasetFormat).
  DatasetFormat format = DatasetFormat::kAuto;
  // Read only the left camera of a stereo dataset (the rig then has baseline 0).
  bool force_mono = false;
  // A calibration file in any format core/io/camera_calibration.h reads (OpenCV, ROS
  // camera_info, Kalibr camchain, dala's own YAML), detected by content. It replaces the
  // dataset's calibration (KITTI calib.txt, synthetic, TUM intrinsics) and is required for image
  // folders and videos; raw images are undistorted (mono) or rectified (stereo) at open. Not
  // used for EuRoC, whose sensor.yaml files are needed for rectification. Empty: the dataset's
  // own calibration.
  std::string calibration_yaml;
  // Image folders: the right camera's folder (empty: monocular). Its images pair with the left
  // ones by file name, or by order when the names differ (then the counts must be equal).
  std::string right_folder;
  // Image folders: a file of frame times in seconds, one per line (KITTI times.txt); empty:
  // the folder's times.txt if present, else `fps`, else times in the file names.
  std::string times_file;
  // Image folders and videos: frame rate (Hz) giving frame i the time i / fps; 0: times from
  // the times file, the file names or the video container.
  double fps = 0;
  // Videos: "mono" (one camera) or "side_by_side" (left and right halves of each frame).
  std::string stereo_layout = "mono";
  // Bags: the image topic (empty: the bag's only one) and the right camera's (empty: mono).
  std::string topic;
  std::string right_topic;
  // Image folders, videos and bags: a ground-truth trajectory of the (raw) left camera: TUM (matched
  // by time) or KITTI (one pose per image or video frame, in order). Empty: none.
  std::string ground_truth;
  // Skip the frames before this index.
  int first_frame = 0;
  // Yield at most this many frames; 0 for all.
  int max_frames = 0;
  // An image that the index (times.txt, data.csv, rgb.txt) names for a frame in the range above
  // but that the folder lacks: false makes OpenDataset throw dala::Error naming it; true logs a
  // warning, and Next() throws FrameError for that frame (the caller skips it). The first frame
  // of the range must exist either way (it fixes the image size). Frames outside the range are
  // not checked.
  bool allow_missing_images = false;
  // Ground truth is interpolated at a frame time only between two samples closer than this
  // (EuRoC has 200 Hz, TUM 100 Hz ground truth); a frame in a larger gap gets none.
  double max_ground_truth_gap_s = 0.1;

  bool IsValid(std::string* why) const;
};

// Opens a dataset folder or a video file. Throws dala::Error on invalid options or a malformed folder.
std::unique_ptr<Dataset> OpenDataset(const std::string& folder,
                                     const DatasetOptions& options = DatasetOptions());

// Detects the format from the folder content: `synth.yaml` -> synthetic, `image_0/` -> KITTI,
// `mav0/` or `cam0/sensor.yaml` -> EuRoC, `rgb.txt` -> TUM, image files (png, jpg) -> images;
// a file named *.bag -> bag, another file -> video. Throws dala::Error listing what was looked for when nothing
// matches.
DatasetFormat DetectDatasetFormat(const std::string& folder);

}  // namespace dala

#endif  // DALA_CORE_IO_DATASET_H_
