#include "core/io/image_sequence.h"

#include <glog/logging.h>

#include <algorithm>
#include <filesystem>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "core/error.h"
#include "core/io/trajectory_io.h"

namespace dala {
namespace {

class ImageSequenceDataset : public Dataset {
 public:
  ImageSequenceDataset(ImageSequence seq, size_t begin, size_t end)
      : seq_(std::move(seq)), begin_(begin), end_(end), next_(begin) {
    if (!seq_.T_w_c0_gt.empty()) {
      Trajectory gt;
      for (size_t i = begin_; i < end_; ++i) {
        if (seq_.T_w_c0_gt[i]) gt.Add(seq_.t_ns[i], *seq_.T_w_c0_gt[i]);
      }
      if (gt.empty()) {
        LOG(WARNING) << seq_.path << ": no frame lies within the ground truth's time range";
      } else {
        ground_truth_ = std::move(gt);
      }
    }
  }

  DatasetFormat format() const override { return seq_.format; }
  const std::string& path() const override { return seq_.path; }
  bool is_stereo() const override { return !seq_.right_files.empty(); }
  const StereoRig& rig() const override { return seq_.rig; }
  size_t size() const override { return end_ - begin_; }
  void Rewind() override { next_ = begin_; }
  const std::optional<Trajectory>& ground_truth() const override { return ground_truth_; }

  bool Next(Frame* frame) override {
    CHECK(frame != nullptr);
    if (next_ >= end_) return false;
    const size_t i = next_++;
    Frame f;
    f.id = FrameId(static_cast<int64_t>(i));
    f.t_ns = seq_.t_ns[i];
    try {
      f.left = Load(seq_.left_files[i], seq_.left_map1, seq_.left_map2);
      if (is_stereo()) f.right = Load(seq_.right_files[i], seq_.right_map1, seq_.right_map2);
    } catch (const Error& e) {
      throw FrameError(f.id, f.t_ns, e.message());
    }
    if (!seq_.T_w_c0_gt.empty()) f.T_w_c0_gt = seq_.T_w_c0_gt[i];
    if (!seq_.T_w_odom.empty()) f.T_w_odom = seq_.T_w_odom[i];
    *frame = std::move(f);
    return true;
  }

 private:
  cv::Mat Load(const std::string& file, const cv::Mat& map1, const cv::Mat& map2) const {
    cv::Mat raw = LoadGrayImage(file, seq_.raw_size, seq_.raw_size_source);
    if (map1.empty()) return raw;
    cv::Mat rectified;
    cv::remap(raw, rectified, map1, map2, cv::INTER_LINEAR, cv::BORDER_CONSTANT);
    return rectified;
  }

  ImageSequence seq_;
  size_t begin_, end_, next_;
  std::optional<Trajectory> ground_truth_;
};

}  // namespace

std::unique_ptr<Dataset> MakeImageSequenceDataset(ImageSequence sequence,
                                                  const DatasetOptions& options) {
  const size_t n = sequence.t_ns.size();
  CHECK_EQ(sequence.left_files.size(), n);
  CHECK(sequence.right_files.empty() || sequence.right_files.size() == n);
  CHECK(sequence.T_w_c0_gt.empty() || sequence.T_w_c0_gt.size() == n);
  CHECK(sequence.T_w_odom.empty() || sequence.T_w_odom.size() == n);
  std::string why;
  CHECK(sequence.rig.IsValid(&why)) << sequence.path << ": " << why;
  CHECK(!sequence.rig.left.HasDistortion()) << "the rig a Dataset yields has no distortion";
  const FrameRange range = SelectFrames(n, options, sequence.path);
  return std::make_unique<ImageSequenceDataset>(std::move(sequence), range.begin, range.end);
}

FrameRange SelectFrames(size_t n, const DatasetOptions& options, const std::string& path) {
  if (n == 0) throw Error() << path << ": the dataset has no frames";
  FrameRange range;
  range.begin = static_cast<size_t>(options.first_frame);
  if (range.begin >= n) {
    throw Error() << "first frame " << options.first_frame << " is past the end of '" << path
                  << "' (" << n << " frames)";
  }
  range.end = n;
  if (options.max_frames > 0) {
    range.end = std::min(n, range.begin + static_cast<size_t>(options.max_frames));
  }
  return range;
}

void CheckMissingImages(const std::vector<MissingImage>& missing, const FrameRange& range,
                        const DatasetOptions& options, const std::string& path) {
  if (missing.empty()) return;
  if (missing.front().frame == range.begin) {
    throw Error() << missing.front().message << " (it is the first frame of the run, which "
                  << "cannot be skipped: --first_frame " << range.begin + 1 << " starts after it)";
  }
  if (!options.allow_missing_images) throw Error() << missing.front().message;
  LOG(WARNING) << path << ": frames to run with a missing image: " << missing.size() << " of "
               << range.end - range.begin
               << "; they are skipped (reported lost). The first: " << missing.front().message;
}

cv::Mat LoadGrayImage(const std::string& path, const cv::Size& expected,
                      const std::string& expected_source) {
  if (!std::filesystem::is_regular_file(path)) {
    throw Error() << "missing image '" << path << "': the file list names it; restore it or "
                  << "remove it from the list";
  }
  cv::Mat image = cv::imread(path, cv::IMREAD_GRAYSCALE);
  if (image.empty()) {
    throw Error() << "cannot decode image '" << path
                  << "' (corrupt or not an image): re-extract the dataset";
  }
  if (!expected.empty() && image.size() != expected) {
    throw Error() << "image '" << path << "' is " << image.cols << "x" << image.rows
                  << ", expected " << expected.width << "x" << expected.height << " (from "
                  << expected_source << "); all images of a sequence must have the size of "
                  << "the calibration";
  }
  return image;
}

void RequireFolder(const std::string& path, const std::string& what) {
  if (!std::filesystem::is_directory(path)) {
    throw Error() << "missing folder '" << path << "' (" << what
                  << "): check the dataset path and layout (docs/datasets.md)";
  }
}

void RequireFile(const std::string& path, const std::string& what) {
  if (!std::filesystem::is_regular_file(path)) {
    throw Error() << "missing file '" << path << "' (" << what
                  << "): check the dataset path and layout (docs/datasets.md)";
  }
}

std::vector<std::optional<Pose>> GroundTruthAtTimes(const Trajectory& ground_truth,
                                                    const std::vector<int64_t>& t_ns,
                                                    int64_t max_gap_ns) {
  // EuRoC stamps pass through a double on reading (~128 ns rounding at epoch times): a frame
  // this close outside the range takes the end sample, and gaps get the same slack.
  constexpr int64_t kEdgeToleranceNs = 1000000;
  std::vector<std::optional<Pose>> out(t_ns.size());
  const auto& poses = ground_truth.poses;
  if (poses.empty()) return out;
  for (size_t i = 0; i < t_ns.size(); ++i) {
    const int64_t t = t_ns[i];
    if (t < poses.front().t_ns - kEdgeToleranceNs || t > poses.back().t_ns + kEdgeToleranceNs) {
      continue;
    }
    if (t <= poses.front().t_ns) {
      out[i] = poses.front().T_w_c;
      continue;
    }
    if (t >= poses.back().t_ns) {
      out[i] = poses.back().T_w_c;
      continue;
    }
    // First sample at or after t; t is strictly inside the range so 0 < k < size.
    const auto it = std::lower_bound(poses.begin(), poses.end(), t,
                                     [](const StampedPose& p, int64_t v) { return p.t_ns < v; });
    const StampedPose& b = *it;
    if (b.t_ns == t) {
      out[i] = b.T_w_c;
      continue;
    }
    const StampedPose& a = *(it - 1);
    if (b.t_ns - a.t_ns > max_gap_ns + kEdgeToleranceNs) continue;
    const double s = static_cast<double>(t - a.t_ns) / static_cast<double>(b.t_ns - a.t_ns);
    out[i] = InterpolatePose(a.T_w_c, b.T_w_c, s);
  }
  return out;
}

std::vector<std::optional<Pose>> ReadGroundTruthFile(const std::string& path,
                                                     const std::vector<int64_t>& t_ns,
                                                     const DatasetOptions& options,
                                                     const Pose& T_c0_c0rect) {
  RequireFile(path, "the ground truth (--ground_truth)");
  const Trajectory gt = ReadTrajectory(path);
  std::vector<std::optional<Pose>> out;
  if (!gt.has_timestamps) {
    if (gt.size() < t_ns.size()) {
      throw Error() << path << " has " << gt.size() << " poses for " << t_ns.size()
                    << " frames: a KITTI ground truth needs one pose per frame, in order (or "
                    << "give a TUM file with times)";
    }
    for (size_t i = 0; i < t_ns.size(); ++i) out.push_back(gt.poses[i].T_w_c);
  } else {
    out = GroundTruthAtTimes(gt, t_ns, NsFromSeconds(options.max_ground_truth_gap_s));
  }
  for (auto& T : out) {
    if (T) T = *T * T_c0_c0rect;
  }
  return out;
}

Pose ApplyCalibration(const CameraCalibration& calibration, bool stereo, ImageSequence* seq) {
  Rectification r = MakeRectification(calibration, stereo);
  seq->rig = r.rig;
  seq->left_map1 = r.left_map1;
  seq->left_map2 = r.left_map2;
  seq->right_map1 = r.right_map1;
  seq->right_map2 = r.right_map2;
  seq->raw_size = cv::Size(calibration.cam0.width, calibration.cam0.height);
  seq->raw_size_source = "the calibration " + calibration.path;
  return r.T_c0_c0rect;
}

PinholeCamera MakeUndistortionMaps(const PinholeCamera& camera, cv::Mat* map1, cv::Mat* map2) {
  cv::Mat K, D;
  cv::Mat(cv::Matx33d(camera.fx, 0, camera.cx, 0, camera.fy, camera.cy, 0, 0, 1)).copyTo(K);
  D = (cv::Mat_<double>(1, 5) << camera.distortion[0], camera.distortion[1], camera.distortion[2],
       camera.distortion[3], camera.distortion[4]);
  const cv::Size size(camera.width, camera.height);
  const cv::Mat new_K = cv::getOptimalNewCameraMatrix(K, D, size, /*alpha=*/0.0, size);
  cv::initUndistortRectifyMap(K, D, cv::Mat(), new_K, size, CV_16SC2, *map1, *map2);
  PinholeCamera out;
  out.width = camera.width;
  out.height = camera.height;
  out.fx = new_K.at<double>(0, 0);
  out.fy = new_K.at<double>(1, 1);
  out.cx = new_K.at<double>(0, 2);
  out.cy = new_K.at<double>(1, 2);
  return out;
}

}  // namespace dala
