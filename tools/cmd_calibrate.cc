// `dala calibrate`: chessboard calibration of a camera or a stereo pair from a folder of images
// or a video, through OpenCV; writes a calibration file `dala run --calibration` reads.
#include <gflags/gflags.h>

#include <algorithm>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>
#include <sstream>

#include "core/error.h"
#include "core/io/atomic_file.h"
#include "core/io/camera_calibration.h"
#include "core/io/image_folder_dataset.h"
#include "tools/command.h"

DECLARE_string(out);            // tools/common_flags.cc
DECLARE_string(right_folder);   // tools/common_flags.cc
DECLARE_string(stereo_layout);  // tools/common_flags.cc
DEFINE_string(board, "9x6", "calibrate: inner corners of the chessboard, columns x rows");
DEFINE_double(square, 1.0,
              "calibrate: side of a board square (the unit of the stereo baseline: give metres "
              "for a metric rig)");
DEFINE_string(model, "radtan", "calibrate: lens model, radtan or fisheye (equidistant)");
DEFINE_string(calibration_format, "opencv",
              "calibrate: format of the file written: opencv, kalibr, ros (one camera) or dala "
              "(one radtan camera)");
DEFINE_string(corners, "",
              "calibrate: folder for the images with the detected corners drawn (default: "
              "OUT's name + _corners)");
DEFINE_int32(frame_step, 15, "calibrate: use every Nth frame of a video");
DEFINE_double(max_blur_px, 4.0,
              "calibrate: reject a view whose board edges are wider than this (pixels, "
              "cv::estimateChessboardSharpness): blurred");

namespace dala {
namespace {
namespace fs = std::filesystem;

struct View {
  std::string name;  // File name, or "frame N" of a video.
  cv::Mat left, right;
};

// The views to calibrate from: the images of a folder (and of --right_folder, by order), or every
// --frame_step-th frame of a video (side by side for a stereo video).
std::vector<View> LoadViews(const std::string& input) {
  std::vector<View> views;
  if (fs::is_directory(input)) {
    const std::vector<std::string> left = ListImageFiles(input);
    if (left.empty()) throw Error() << input << ": holds no image (png, jpg, ...)";
    std::vector<std::string> right;
    if (!FLAGS_right_folder.empty()) {
      right = ListImageFiles(FLAGS_right_folder);
      if (right.size() != left.size()) {
        throw Error() << FLAGS_right_folder << ": holds " << right.size() << " images for the "
                      << left.size() << " of " << input
                      << ": give one right image per left image (same order)";
      }
    }
    for (size_t i = 0; i < left.size(); ++i) {
      View v;
      v.name = fs::path(left[i]).filename().string();
      v.left = cv::imread(left[i], cv::IMREAD_COLOR);
      if (!right.empty()) {
        v.name += "+" + fs::path(right[i]).filename().string();
        v.right = cv::imread(right[i], cv::IMREAD_COLOR);
      }
      views.push_back(std::move(v));
    }
    return views;
  }
  if (!fs::is_regular_file(input)) {
    throw Error() << "missing image folder or video '" << input << "': check the path";
  }
  cv::VideoCapture cap(input, cv::CAP_FFMPEG);
  if (!cap.isOpened()) {
    throw Error() << "cannot open video '" << input << "': not a video FFmpeg knows, or corrupt";
  }
  const bool side_by_side = FLAGS_stereo_layout == "side_by_side";
  cv::Mat frame;
  for (int i = 0; cap.read(frame); ++i) {
    if (i % std::max(1, FLAGS_frame_step) != 0) continue;
    View v;
    v.name = "frame " + std::to_string(i);
    if (side_by_side) {
      const int w = frame.cols / 2;
      v.left = frame(cv::Rect(0, 0, w, frame.rows)).clone();
      v.right = frame(cv::Rect(w, 0, w, frame.rows)).clone();
    } else {
      v.left = frame.clone();
    }
    views.push_back(std::move(v));
  }
  if (views.empty()) {
    throw Error() << "video '" << input << "': no frame could be decoded (the codec is the "
                  << "problem): re-encode it (ffmpeg -i IN -c:v libx264 OUT.mp4)";
  }
  return views;
}

cv::Size ParseBoard(const std::string& text) {
  int c = 0, r = 0;
  char x = 0;
  std::istringstream is(text);
  if (!(is >> c >> x >> r) || x != 'x' || c < 2 || r < 2) {
    throw Error() << "--board '" << text << "': expected the inner corners as COLSxROWS, e.g. 9x6";
  }
  return {c, r};
}

// Corners of one image, or why there are none.
bool Detect(const cv::Mat& image, cv::Size board, std::vector<cv::Point2f>* corners,
            std::string* why) {
  cv::Mat gray;
  cv::cvtColor(image, gray, cv::COLOR_BGR2GRAY);
  if (!cv::findChessboardCorners(gray, board, *corners,
                                 cv::CALIB_CB_ADAPTIVE_THRESH | cv::CALIB_CB_NORMALIZE_IMAGE)) {
    *why = "board not found";
    return false;
  }
  cv::cornerSubPix(gray, *corners, cv::Size(11, 11), cv::Size(-1, -1),
                   cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 30, 0.01));
  const cv::Scalar sharpness = cv::estimateChessboardSharpness(gray, board, *corners);
  if (sharpness[0] > FLAGS_max_blur_px) {
    std::ostringstream os;
    os << "blurred (board edges " << std::fixed << std::setprecision(1) << sharpness[0]
       << " px wide > --max_blur_px " << FLAGS_max_blur_px << ")";
    *why = os.str();
    return false;
  }
  return true;
}

void WriteImage(const std::string& path, const cv::Mat& image) {
  const std::string tmp = path + ".tmp.png";
  if (!cv::imwrite(tmp, image)) throw Error() << path << ": cannot write the image";
  fs::rename(tmp, path);
}

RawCamera CameraOf(const cv::Mat& K, const cv::Mat& D, cv::Size size, LensModel model) {
  RawCamera c;
  c.width = size.width;
  c.height = size.height;
  c.fx = K.at<double>(0, 0);
  c.fy = K.at<double>(1, 1);
  c.cx = K.at<double>(0, 2);
  c.cy = K.at<double>(1, 2);
  c.model = model;
  const cv::Mat d = D.reshape(1, 1);
  for (int i = 0; i < std::min(5, d.cols); ++i) c.distortion[i] = d.at<double>(0, i);
  return c;
}

struct MonoResult {
  cv::Mat K, D;
  double rms = 0;
  std::vector<double> per_view;  // RMS reprojection error per view (px).
};

MonoResult CalibrateOne(const std::vector<std::vector<cv::Point3f>>& object,
                        const std::vector<std::vector<cv::Point2f>>& image, cv::Size size,
                        LensModel model) {
  MonoResult r;
  std::vector<cv::Mat> rvecs, tvecs;
  if (model == LensModel::kFisheye) {
    r.K = cv::Mat::eye(3, 3, CV_64F);
    r.D = cv::Mat::zeros(4, 1, CV_64F);
    std::vector<std::vector<cv::Point3d>> obj_d;
    std::vector<std::vector<cv::Point2d>> img_d;
    for (size_t i = 0; i < object.size(); ++i) {
      obj_d.emplace_back(object[i].begin(), object[i].end());
      img_d.emplace_back(image[i].begin(), image[i].end());
    }
    r.rms = cv::fisheye::calibrate(
        obj_d, img_d, size, r.K, r.D, rvecs, tvecs,
        cv::fisheye::CALIB_RECOMPUTE_EXTRINSIC | cv::fisheye::CALIB_FIX_SKEW,
        cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 100, 1e-9));
    for (size_t i = 0; i < object.size(); ++i) {
      std::vector<cv::Point2d> projected;
      cv::fisheye::projectPoints(obj_d[i], projected, rvecs[i], tvecs[i], r.K, r.D);
      double sum = 0;
      for (size_t k = 0; k < projected.size(); ++k) {
        const cv::Point2d e = projected[k] - img_d[i][k];
        sum += e.dot(e);
      }
      r.per_view.push_back(std::sqrt(sum / projected.size()));
    }
  } else {
    cv::Mat std_in, std_ex, per_view;
    r.rms = cv::calibrateCamera(object, image, size, r.K, r.D, rvecs, tvecs, std_in, std_ex,
                                per_view, 0);
    for (int i = 0; i < per_view.rows; ++i) r.per_view.push_back(per_view.at<double>(i));
  }
  return r;
}

int RunCalibrate(const std::vector<std::string>& args) {
  if (args.size() != 1) {
    throw Error() << "expected one image folder or video, got " << args.size()
                  << " arguments; usage: dala calibrate INPUT --out FILE";
  }
  if (FLAGS_out.empty()) throw Error() << "--out FILE is required (the calibration to write)";
  const cv::Size board = ParseBoard(FLAGS_board);
  if (!(FLAGS_square > 0)) throw Error() << "--square " << FLAGS_square << " must be > 0";
  if (FLAGS_model != "radtan" && FLAGS_model != "fisheye") {
    throw Error() << "--model '" << FLAGS_model << "': use radtan or fisheye";
  }
  if (FLAGS_stereo_layout != "mono" && FLAGS_stereo_layout != "side_by_side") {
    throw Error() << "--stereo_layout '" << FLAGS_stereo_layout << "': use mono or side_by_side";
  }
  const LensModel model = FLAGS_model == "fisheye" ? LensModel::kFisheye : LensModel::kRadtan;
  CalibrationFormat format = CalibrationFormat::kOpenCv;
  bool known_format = false;
  for (CalibrationFormat f : {CalibrationFormat::kOpenCv, CalibrationFormat::kKalibr,
                              CalibrationFormat::kRos, CalibrationFormat::kDala}) {
    if (FLAGS_calibration_format == CalibrationFormatName(f)) {
      format = f;
      known_format = true;
    }
  }
  if (!known_format) {
    throw Error() << "--calibration_format '" << FLAGS_calibration_format
                  << "': use opencv, kalibr, ros or dala";
  }

  const std::vector<View> views = LoadViews(args[0]);
  const bool stereo = !views.front().right.empty();
  if (stereo && (format == CalibrationFormat::kRos || format == CalibrationFormat::kDala)) {
    throw Error() << "--calibration_format " << FLAGS_calibration_format << " holds one camera "
                  << "(dala's own: a rectified pair only): write a stereo calibration as opencv "
                  << "or kalibr";
  }
  const std::string corners_dir =
      FLAGS_corners.empty() ? (fs::path(FLAGS_out).replace_extension().string() + "_corners")
                            : FLAGS_corners;
  CreateDirectories(corners_dir);

  std::vector<cv::Point3f> board_points;
  for (int r = 0; r < board.height; ++r) {
    for (int c = 0; c < board.width; ++c) {
      board_points.emplace_back(static_cast<float>(c * FLAGS_square),
                                static_cast<float>(r * FLAGS_square), 0.f);
    }
  }
  cv::Size size;
  std::vector<std::vector<cv::Point3f>> object;
  std::vector<std::vector<cv::Point2f>> left_points, right_points;
  std::vector<std::string> used;
  int rejected = 0;
  for (size_t i = 0; i < views.size(); ++i) {
    const View& v = views[i];
    std::string why;
    std::vector<cv::Point2f> left, right;
    if (v.left.empty() || (stereo && v.right.empty())) {
      why = "unreadable image";
    } else if (size.empty()) {
      size = v.left.size();
    }
    if (why.empty() && (v.left.size() != size || (stereo && v.right.size() != size))) {
      why = "image size differs from the first view's";
    }
    if (why.empty() && !Detect(v.left, board, &left, &why) && stereo) why = "left: " + why;
    if (why.empty() && stereo && !Detect(v.right, board, &right, &why)) why = "right: " + why;
    if (!why.empty()) {
      std::cout << "rejected    " << v.name << ": " << why << "\n";
      ++rejected;
      continue;
    }
    cv::Mat drawn = v.left.clone();
    cv::drawChessboardCorners(drawn, board, left, true);
    if (stereo) {
      cv::Mat right_drawn = v.right.clone();
      cv::drawChessboardCorners(right_drawn, board, right, true);
      cv::hconcat(drawn, right_drawn, drawn);
    }
    std::ostringstream name;
    name << corners_dir << "/" << std::setw(4) << std::setfill('0') << i << ".png";
    WriteImage(name.str(), drawn);
    object.push_back(board_points);
    left_points.push_back(left);
    if (stereo) right_points.push_back(right);
    used.push_back(v.name);
  }
  constexpr size_t kMinViews = 4;
  if (used.size() < kMinViews) {
    throw Error() << args[0] << ": too few views with the board (" << used.size() << " of "
                  << views.size() << ", " << kMinViews << " needed): check --board (inner "
                  << "corners, " << FLAGS_board << " now) and take more sharp views of the "
                  << "whole board at various angles";
  }

  const MonoResult l = CalibrateOne(object, left_points, size, model);
  CameraCalibration calibration;
  calibration.cam0 = CameraOf(l.K, l.D, size, model);
  double rms = l.rms;
  std::vector<double> per_view = l.per_view;
  if (stereo) {
    const MonoResult r = CalibrateOne(object, right_points, size, model);
    cv::Mat R, T;
    cv::Mat K1 = l.K.clone(), D1 = l.D.clone(), K2 = r.K.clone(), D2 = r.D.clone();
    if (model == LensModel::kFisheye) {
      std::vector<std::vector<cv::Point3d>> obj_d;
      std::vector<std::vector<cv::Point2d>> l_d, r_d;
      for (size_t i = 0; i < object.size(); ++i) {
        obj_d.emplace_back(object[i].begin(), object[i].end());
        l_d.emplace_back(left_points[i].begin(), left_points[i].end());
        r_d.emplace_back(right_points[i].begin(), right_points[i].end());
      }
      rms = cv::fisheye::stereoCalibrate(obj_d, l_d, r_d, K1, D1, K2, D2, size, R, T,
                                         cv::fisheye::CALIB_FIX_INTRINSIC);
    } else {
      cv::Mat E, F, per_view_pair;
      rms = cv::stereoCalibrate(object, left_points, right_points, K1, D1, K2, D2, size, R, T, E,
                                F, per_view_pair, cv::CALIB_FIX_INTRINSIC);
      per_view.clear();
      for (int i = 0; i < per_view_pair.rows; ++i) {
        per_view.push_back(0.5 * (per_view_pair.at<double>(i, 0) + per_view_pair.at<double>(i, 1)));
      }
    }
    calibration.cam1 = CameraOf(r.K, r.D, size, model);
    Eigen::Matrix3d Re;
    for (int a = 0; a < 3; ++a) {
      for (int b = 0; b < 3; ++b) Re(a, b) = R.at<double>(a, b);
    }
    calibration.T_c1_c0 = Orthonormalized(
        MakePose(Re, Eigen::Vector3d(T.at<double>(0), T.at<double>(1), T.at<double>(2))));
    std::cout << "left        RMS " << std::fixed << std::setprecision(3) << l.rms
              << " px; right RMS " << r.rms << " px\n";
  }
  calibration.path = FLAGS_out;
  WriteCameraCalibration(FLAGS_out, calibration, format);

  std::cout << std::fixed << std::setprecision(3);
  for (size_t i = 0; i < used.size(); ++i) {
    std::cout << "view        " << used[i] << ": " << per_view[i] << " px\n";
  }
  const RawCamera& c = calibration.cam0;
  std::cout << "views       " << used.size() << " used, " << rejected << " rejected, of "
            << views.size() << "\n"
            << "RMS         " << rms << " px reprojection error"
            << (stereo ? " (stereo, intrinsics held)" : "") << "\n"
            << "camera      " << LensModelName(model) << " " << size.width << "x" << size.height
            << ", fx " << c.fx << " fy " << c.fy << " cx " << c.cx << " cy " << c.cy << "\n"
            << "distortion  " << std::setprecision(5);
  for (int i = 0; i < (model == LensModel::kFisheye ? 4 : 5); ++i) {
    std::cout << c.distortion[i] << " ";
  }
  std::cout << "\n";
  if (stereo) {
    const Eigen::Vector3d t = calibration.T_c1_c0.translation();
    std::cout << "baseline    " << std::setprecision(4) << t.norm()
              << " (the unit of --square), T_c1_c0 translation " << t.transpose() << "\n";
  }
  std::cout << "written     " << FLAGS_out << " (" << CalibrationFormatName(format)
            << "), corners drawn in " << corners_dir << "/\n";
  return 0;
}

const CommandRegistrar kRegistrar(
    {"calibrate", "calibrate a camera or a stereo pair from chessboard images or a video",
     "dala calibrate INPUT --out FILE [--board 9x6] [--square S] [--model radtan|fisheye]\n"
     "         [--right_folder DIR] [--stereo_layout side_by_side] [--frame_step N]\n"
     "         [--calibration_format opencv|kalibr|ros|dala] [--corners DIR] [--max_blur_px P]\n\n"
     "INPUT is a folder of images (sorted by name) or a video (every --frame_step-th frame) of a\n"
     "chessboard with --board inner corners, seen whole from various angles and distances.\n"
     "Finds the corners (cv::findChessboardCorners, cornerSubPix), rejects the views where the\n"
     "board is not found or blurred (saying which and why), calibrates with\n"
     "cv::calibrateCamera or cv::fisheye::calibrate, and for a pair (--right_folder, or a\n"
     "side-by-side video) cv::stereoCalibrate with the intrinsics held; prints the RMS and\n"
     "per-view reprojection errors, draws the corners found into --corners (default OUT's name\n"
     "+ _corners/) and writes FILE, which `dala run --calibration FILE` reads. The stereo\n"
     "baseline is in the unit of --square (give the square's side in metres).",
     &RunCalibrate, __FILE__});

}  // namespace
}  // namespace dala
