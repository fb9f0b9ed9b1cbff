#ifndef DALA_TOOLS_REPORT_FRAME_VIDEO_H_
#define DALA_TOOLS_REPORT_FRAME_VIDEO_H_

// `dala run --video FILE.mp4`: a video of what the frontend saw, one picture per frame: the left
// image with its tracked points coloured by track age (red: new, through yellow, to green: 10
// frames or more), each stereo point's match in the right image as a horizontal segment to its
// abscissa there (the disparity), a header with the frame, the tracking state, the keyframe flag,
// counts and a recognised loop, and a small top view of the path so far (the first camera's x-z
// plane, x right, z up: the ground for a camera looking ahead). OpenCV's VideoWriter, codec mp4v;
// where it cannot write that (an OpenCV without an MPEG-4 encoder), Motion-JPEG into FILE with
// the extension .avi, said on stderr. The frame rate is the dataset's (its first two frames).
//
// The file is written as a temporary beside FILE and renamed at Close(), so that no half-written
// video is ever left under FILE (the destructor removes the temporary of an unclosed video).

#include <chrono>
#include <opencv2/core.hpp>
#include <opencv2/videoio.hpp>
#include <optional>
#include <string>
#include <vector>

#include "backend/system.h"
#include "core/frame_measurement.h"
#include "core/geometry.h"

namespace dala::report {

class FrameVideo {
 public:
  // `path` must end in .mp4 or .avi (dala::Error otherwise, saying so); its folder must exist.
  explicit FrameVideo(const std::string& path);
  ~FrameVideo();
  FrameVideo(const FrameVideo&) = delete;
  FrameVideo& operator=(const FrameVideo&) = delete;

  // Draws one frame: its left image, the frontend's measurement of it, its stats and its pose
  // (none: not placed). Throws dala::Error when the writer cannot be opened in either format.
  void Add(const cv::Mat& left, const FrameMeasurement& measurement, const FrameStats& stats,
           const std::optional<Pose>& T_w_c);
  // Finishes the file and moves it into place; returns its path (FILE, or FILE with .avi).
  // Nothing is written for a run without frames (returns "").
  std::string Close();

  int frames() const { return frames_; }
  // Drawing and encoding time per frame so far (milliseconds).
  double ms_per_frame() const { return frames_ > 0 ? total_ms_ / frames_ : 0.0; }

 private:
  void Open(double fps, cv::Size size);
  cv::Mat Draw(const cv::Mat& left, const FrameMeasurement& m, const FrameStats& s) const;

  std::string path_;       // Where the video goes.
  std::string temp_path_;  // Where it is written until Close().
  cv::VideoWriter writer_;
  std::optional<cv::Mat> first_;  // The first picture, until the second gives the frame rate.
  int64_t first_t_ns_ = 0;
  int frames_ = 0;
  double total_ms_ = 0.0;
  std::vector<Eigen::Vector2d> path_xz_;  // Top view: positions in the first camera's x-z plane.
  std::optional<Pose> T_w_first_;
};

}  // namespace dala::report

#endif  // DALA_TOOLS_REPORT_FRAME_VIDEO_H_
