#include "tools/report/frame_video.h"

#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <opencv2/imgproc.hpp>

#include "core/error.h"

namespace dala::report {
namespace {

constexpr int kHeaderPx = 36;  // The text line above the image.

bool EndsWith(const std::string& s, const std::string& tail) {
  return s.size() >= tail.size() && s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
}

// Even sizes: the MPEG-4 encoder needs them.
int Even(int v) { return v + (v % 2); }

// Red (a new track) through yellow to green (10 frames or more).
cv::Scalar AgeColour(int track_length) {
  const double f = std::min(1.0, (track_length - 1) / 9.0);
  return f < 0.5 ? cv::Scalar(0, 255 * 2 * f, 255) : cv::Scalar(0, 255, 255 * 2 * (1 - f));
}

std::string TempPathFor(const std::string& path) {
  const std::filesystem::path p(path);
  return (p.parent_path() /
          ("." + p.stem().string() + ".tmp." + std::to_string(getpid()) + p.extension().string()))
      .string();
}

}  // namespace

FrameVideo::FrameVideo(const std::string& path) : path_(path) {
  if (!EndsWith(path, ".mp4") && !EndsWith(path, ".avi")) {
    throw Error() << "--video " << path << ": give a file ending in .mp4 (MPEG-4) or .avi "
                  << "(Motion-JPEG)";
  }
  const std::filesystem::path parent = std::filesystem::path(path).parent_path();
  if (!parent.empty() && !std::filesystem::is_directory(parent)) {
    throw Error() << "--video " << path << ": the folder " << parent.string()
                  << " does not exist; create it or write the video elsewhere";
  }
  temp_path_ = TempPathFor(path_);
}

FrameVideo::~FrameVideo() {
  if (writer_.isOpened()) writer_.release();
  std::error_code ignored;
  if (!temp_path_.empty()) std::filesystem::remove(temp_path_, ignored);
}

void FrameVideo::Open(double fps, cv::Size size) {
  if (EndsWith(path_, ".mp4") &&
      writer_.open(temp_path_, cv::VideoWriter::fourcc('m', 'p', '4', 'v'), fps, size, true)) {
    return;
  }
  if (EndsWith(path_, ".mp4")) {
    // No MPEG-4 encoder in this OpenCV: Motion-JPEG, which every OpenCV writes.
    const std::string avi = path_.substr(0, path_.size() - 4) + ".avi";
    std::cerr << "[run] --video: OpenCV cannot write MPEG-4 (mp4v) here; writing Motion-JPEG "
              << "to " << avi << " instead\n";
    path_ = avi;
    temp_path_ = TempPathFor(path_);
  }
  if (!writer_.open(temp_path_, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), fps, size, true)) {
    throw Error() << "--video " << path_ << ": OpenCV's VideoWriter cannot write it (neither "
                  << "mp4v nor MJPG); check that the folder is writable and OpenCV has videoio "
                  << "with FFmpeg or its built-in AVI writer";
  }
}

cv::Mat FrameVideo::Draw(const cv::Mat& left, const FrameMeasurement& m,
                         const FrameStats& s) const {
  cv::Mat canvas(Even(left.rows + kHeaderPx), Even(left.cols), CV_8UC3, cv::Scalar(24, 24, 24));
  cv::Mat image = canvas(cv::Rect(0, kHeaderPx, left.cols, left.rows));
  if (left.channels() == 1) {
    cv::cvtColor(left, image, cv::COLOR_GRAY2BGR);
  } else {
    left.copyTo(image);
  }
  int stereo = 0;
  for (const FeatureObservation& o : m.observations) {
    const cv::Point2d uv(o.uv.x(), o.uv.y());
    if (o.has_stereo()) {
      ++stereo;
      cv::line(image, uv, cv::Point2d(*o.u_right, o.uv.y()), cv::Scalar(255, 200, 0), 1,
               cv::LINE_AA);
    }
    cv::circle(image, uv, 3, AgeColour(o.track_length), 1, cv::LINE_AA);
  }
  // Header: frame, state, keyframe, counts, loop.
  const bool lost = s.status == TrackingStatus::kLost;
  const cv::Scalar state_colour = lost ? cv::Scalar(60, 60, 255)
                                  : s.status == TrackingStatus::kTracking
                                      ? cv::Scalar(80, 220, 80)
                                      : cv::Scalar(180, 180, 180);
  const double scale = left.cols >= 800 ? 0.55 : 0.42;
  int x = 6;
  const auto text = [&](const std::string& t, const cv::Scalar& colour) {
    cv::putText(canvas, t, cv::Point(x, 24), cv::FONT_HERSHEY_SIMPLEX, scale, colour, 1,
                cv::LINE_AA);
    int baseline = 0;
    x += cv::getTextSize(t, cv::FONT_HERSHEY_SIMPLEX, scale, 1, &baseline).width + 12;
  };
  text("frame " + std::to_string(s.frame.value), cv::Scalar(230, 230, 230));
  text(TrackingStatusName(s.status), state_colour);
  if (s.keyframe) text("KEYFRAME", cv::Scalar(255, 150, 60));
  text(std::to_string(s.features) + " points, " + std::to_string(s.tracked) + " tracked, " +
           std::to_string(stereo) + " stereo",
       cv::Scalar(230, 230, 230));
  if (s.loop_old_frame) {
    text(std::string(s.loop_closed ? "loop closed" : "loop") + " to frame " +
             std::to_string(s.loop_old_frame->value),
         cv::Scalar(80, 255, 80));
  }
  // Top view of the path so far, at the image's top right.
  const int side = std::max(40, std::min(160, left.rows / 3));
  const cv::Rect inset(left.cols - side - 6, 6, side, side);
  if (!path_xz_.empty() && inset.x > 0) {
    cv::Mat roi = image(inset);
    roi *= 0.35;
    Eigen::Vector2d lo = path_xz_.front(), hi = path_xz_.front();
    for (const Eigen::Vector2d& p : path_xz_) {
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
    const double extent = std::max({hi.x() - lo.x(), hi.y() - lo.y(), 1.0});
    const Eigen::Vector2d centre = 0.5 * (lo + hi);
    const double px = (side - 12) / extent;
    const auto to_px = [&](const Eigen::Vector2d& p) {
      return cv::Point2d(side / 2.0 + (p.x() - centre.x()) * px,
                         side / 2.0 - (p.y() - centre.y()) * px);
    };
    for (size_t i = 1; i < path_xz_.size(); ++i) {
      cv::line(roi, to_px(path_xz_[i - 1]), to_px(path_xz_[i]), cv::Scalar(48, 48, 255), 1,
               cv::LINE_AA);
    }
    cv::circle(roi, to_px(path_xz_.back()), 3, cv::Scalar(255, 0, 255), cv::FILLED, cv::LINE_AA);
    cv::rectangle(image, inset, cv::Scalar(160, 160, 160), 1);
  }
  return canvas;
}

void FrameVideo::Add(const cv::Mat& left, const FrameMeasurement& measurement,
                     const FrameStats& stats, const std::optional<Pose>& T_w_c) {
  const auto start = std::chrono::steady_clock::now();
  if (T_w_c) {
    if (!T_w_first_) T_w_first_ = *T_w_c;
    const Eigen::Vector3d p = T_w_first_->inverse() * T_w_c->translation();
    path_xz_.emplace_back(p.x(), p.z());
  }
  const cv::Mat picture = Draw(left, measurement, stats);
  if (frames_ == 0) {
    first_ = picture;
    first_t_ns_ = stats.t_ns;
  } else {
    if (!writer_.isOpened()) {
      // The frame rate from the first two frames (10 Hz when they carry no time).
      const double dt = (stats.t_ns - first_t_ns_) * 1e-9;
      Open(dt > 1e-4 ? std::clamp(1.0 / dt, 1.0, 240.0) : 10.0, picture.size());
      writer_.write(*first_);
      first_.reset();
    }
    writer_.write(picture);
  }
  ++frames_;
  total_ms_ +=
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

std::string FrameVideo::Close() {
  if (frames_ == 0) return "";
  if (!writer_.isOpened()) {
    // A single frame: its picture at 10 Hz.
    Open(10.0, first_->size());
    writer_.write(*first_);
    first_.reset();
  }
  writer_.release();
  std::error_code error;
  std::filesystem::rename(temp_path_, path_, error);
  if (error) {
    throw Error() << "--video " << path_ << ": cannot move " << temp_path_ << " there ("
                  << error.message() << ")";
  }
  temp_path_.clear();
  return path_;
}

}  // namespace dala::report
