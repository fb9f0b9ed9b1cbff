#include "core/io/video_dataset.h"

#include <glog/logging.h>

#include <filesystem>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include "core/error.h"
#include "core/io/camera_calibration.h"
#include "core/io/image_sequence.h"

namespace dala {
namespace fs = std::filesystem;
namespace {

std::string FourCc(const cv::VideoCapture& cap) {
  const int code = static_cast<int>(cap.get(cv::CAP_PROP_FOURCC));
  std::string s;
  for (int i = 0; i < 4; ++i) {
    const char c = static_cast<char>((code >> (8 * i)) & 0xff);
    s += (c >= 32 && c < 127) ? c : '?';
  }
  return s;
}

cv::VideoCapture OpenCapture(const std::string& path) {
  if (!fs::is_regular_file(path)) {
    throw Error() << "missing video file '" << path << "': check the path";
  }
  if (fs::file_size(path) == 0) {
    throw Error() << "video file '" << path << "' is empty (0 bytes): the file is the problem "
                  << "(an interrupted copy or recording); copy it again";
  }
  cv::VideoCapture cap(path, cv::CAP_FFMPEG);
  if (!cap.isOpened()) {
    throw Error() << "cannot open video '" << path << "': FFmpeg (through OpenCV) does not "
                  << "recognise it as a video, so the file is the problem (not a video, "
                  << "truncated or corrupt, or a container FFmpeg does not know); check it with "
                  << "a video player or re-encode it (ffmpeg -i IN -c:v libx264 OUT.mp4)";
  }
  return cap;
}

cv::Mat ToGray(const cv::Mat& frame) {
  if (frame.channels() == 1) return frame;
  cv::Mat gray;
  cv::cvtColor(frame, gray, frame.channels() == 4 ? cv::COLOR_BGRA2GRAY : cv::COLOR_BGR2GRAY);
  return gray;
}

class VideoDataset : public Dataset {
 public:
  VideoDataset(std::string path, bool side_by_side, bool stereo, Rectification rect, cv::Size raw_size,
               std::vector<int64_t> t_ns, size_t begin, std::vector<std::optional<Pose>> gt)
      : path_(std::move(path)),
        side_by_side_(side_by_side),
        stereo_(stereo),
        rect_(std::move(rect)),
        raw_size_(raw_size),
        t_ns_(std::move(t_ns)),
        begin_(begin),
        gt_(std::move(gt)) {
    if (!gt_.empty()) {
      Trajectory trajectory;
      for (size_t i = begin_; i < t_ns_.size(); ++i) {
        if (gt_[i]) trajectory.Add(t_ns_[i], *gt_[i]);
      }
      if (!trajectory.empty()) ground_truth_ = std::move(trajectory);
    }
    Rewind();
  }

  DatasetFormat format() const override { return DatasetFormat::kVideo; }
  const std::string& path() const override { return path_; }
  bool is_stereo() const override { return stereo_; }
  const StereoRig& rig() const override { return rect_.rig; }
  size_t size() const override { return t_ns_.size() - begin_; }
  const std::optional<Trajectory>& ground_truth() const override { return ground_truth_; }

  void Rewind() override {
    cap_ = OpenCapture(path_);
    for (size_t i = 0; i < begin_; ++i) cap_.grab();
    next_ = begin_;
  }

  bool Next(Frame* frame) override {
    CHECK(frame != nullptr);
    if (next_ >= t_ns_.size()) return false;
    const size_t i = next_++;
    Frame f;
    f.id = FrameId(static_cast<int64_t>(i));
    f.t_ns = t_ns_[i];
    cv::Mat raw;
    if (!cap_.read(raw) || raw.empty()) {
      throw FrameError(f.id, f.t_ns,
                       "video '" + path_ + "': frame " + std::to_string(i) + " cannot be decoded");
    }
    const cv::Mat gray = ToGray(raw);
    const cv::Size expected(side_by_side_ ? 2 * raw_size_.width : raw_size_.width,
                            raw_size_.height);
    if (gray.size() != expected) {
      throw FrameError(f.id, f.t_ns,
                       "video '" + path_ + "': frame " + std::to_string(i) + " is " +
                           std::to_string(gray.cols) + "x" + std::to_string(gray.rows) +
                           ", expected " + std::to_string(expected.width) + "x" +
                           std::to_string(expected.height));
    }
    if (side_by_side_) {
      f.left = Remap(gray(cv::Rect(0, 0, raw_size_.width, raw_size_.height)), rect_.left_map1,
                     rect_.left_map2);
      if (stereo_) {
        f.right = Remap(gray(cv::Rect(raw_size_.width, 0, raw_size_.width, raw_size_.height)),
                        rect_.right_map1, rect_.right_map2);
      }
    } else {
      f.left = Remap(gray, rect_.left_map1, rect_.left_map2);
    }
    if (!gt_.empty()) f.T_w_c0_gt = gt_[i];
    *frame = std::move(f);
    return true;
  }

 private:
  static cv::Mat Remap(const cv::Mat& raw, const cv::Mat& map1, const cv::Mat& map2) {
    if (map1.empty()) return raw.clone();
    cv::Mat out;
    cv::remap(raw, out, map1, map2, cv::INTER_LINEAR, cv::BORDER_CONSTANT);
    return out;
  }

  std::string path_;
  bool side_by_side_;  // The frame holds the left and right images side by side.
  bool stereo_;        // Both are yielded (false: the left half only).
  Rectification rect_;
  cv::Size raw_size_;  // Of one camera's image.
  std::vector<int64_t> t_ns_;  // Frames 0 .. end of the range.
  size_t begin_;
  std::vector<std::optional<Pose>> gt_;
  std::optional<Trajectory> ground_truth_;
  cv::VideoCapture cap_;
  size_t next_ = 0;
};

}  // namespace

std::unique_ptr<Dataset> OpenVideoDataset(const std::string& path, const DatasetOptions& options) {
  cv::VideoCapture cap = OpenCapture(path);
  cv::Mat first;
  if (!cap.read(first) || first.empty()) {
    throw Error() << "video '" << path << "': the container opens but its video stream (codec '"
                  << FourCc(cap) << "') cannot be decoded, so the codec is the problem: this "
                  << "OpenCV's FFmpeg lacks a decoder for it; re-encode the video "
                  << "(ffmpeg -i IN -c:v libx264 OUT.mp4, or -c:v mjpeg OUT.avi)";
  }
  if (options.calibration_yaml.empty()) {
    throw Error() << "video '" << path << "' needs its camera calibration: give --calibration "
                  << "FILE (OpenCV, ROS camera_info, Kalibr or dala YAML; `dala calibrate` "
                  << "writes one from a video of a chessboard; docs/datasets.md, \"Your own "
                  << "camera\")";
  }
  const bool side_by_side = options.stereo_layout == "side_by_side";
  const bool stereo = side_by_side && !options.force_mono;
  const CameraCalibration calibration = ReadCameraCalibration(options.calibration_yaml);
  const cv::Size raw_size(calibration.cam0.width, calibration.cam0.height);
  const cv::Size expected(side_by_side ? 2 * raw_size.width : raw_size.width, raw_size.height);
  if (first.size() != expected) {
    throw Error() << "video '" << path << "' has " << first.cols << "x" << first.rows
                  << " frames, but the calibration " << calibration.path << " is for "
                  << raw_size.width << "x" << raw_size.height
                  << (side_by_side ? " per half of a side-by-side frame" : "")
                  << ": calibrate the camera at the video's resolution (dala calibrate on "
                  << "frames of the same size)"
                  << (side_by_side ? "" : ", or give --stereo_layout side_by_side for a "
                                          "stereo video");
  }
  Rectification rect = MakeRectification(calibration, stereo);

  // Index the frames of the run: the container's times, or i / fps.
  const size_t first_needed = static_cast<size_t>(options.first_frame);
  const size_t end_wanted =
      options.max_frames > 0 ? first_needed + static_cast<size_t>(options.max_frames) : SIZE_MAX;
  std::vector<int64_t> t_ns;
  t_ns.push_back(NsFromSeconds(1e-3 * cap.get(cv::CAP_PROP_POS_MSEC)));
  while (t_ns.size() < end_wanted && cap.grab()) {
    t_ns.push_back(NsFromSeconds(1e-3 * cap.get(cv::CAP_PROP_POS_MSEC)));
  }
  bool increasing = true;
  for (size_t i = 1; i < t_ns.size(); ++i) increasing = increasing && t_ns[i] > t_ns[i - 1];
  double fps = options.fps;
  if (fps <= 0 && !increasing) {
    fps = cap.get(cv::CAP_PROP_FPS);
    if (!(fps > 0)) {
      throw Error() << "video '" << path << "' has no usable frame times (they do not increase) "
                    << "and no frame rate: give it with --fps";
    }
    LOG(WARNING) << path << ": the container's frame times do not increase; using its frame "
                 << "rate " << fps << " Hz";
  }
  if (fps > 0) {
    for (size_t i = 0; i < t_ns.size(); ++i) {
      t_ns[i] = NsFromSeconds(static_cast<double>(i) / fps);
    }
  }
  const FrameRange range = SelectFrames(t_ns.size(), options, path);
  std::vector<std::optional<Pose>> gt;
  if (!options.ground_truth.empty()) {
    gt = ReadGroundTruthFile(options.ground_truth, t_ns, options, rect.T_c0_c0rect);
  }
  LOG(INFO) << path << ": video, codec " << FourCc(cap) << ", " << first.cols << "x" << first.rows
            << ", frames " << range.begin << ".." << range.end - 1 << " of the run";
  if (!stereo) rect.rig.baseline = 0;
  return std::make_unique<VideoDataset>(path, side_by_side, stereo, std::move(rect), raw_size, std::move(t_ns),
                                        range.begin, std::move(gt));
}

}  // namespace dala
