// `dala calibrate` (the binary) on the chessboard images Debian's opencv-doc ships (left01..14,
// right01..14 of OpenCV's samples/data; skipped where the package is absent): the intrinsics
// agree with what OpenCV publishes for them (samples/data/left_intrinsics.yml), the stereo
// baseline with the board poses of each pair, bad views are rejected with the reason, and
// `dala run` reads the file written.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include "core/io/camera_calibration.h"
#include "tests/dala_cli.h"
#include "tests/test_util.h"

namespace dala {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;
using testing::ReadAll;
using testing::TempDir;

const char* kDocData = "/usr/share/doc/opencv-doc/examples/data";

#define SKIP_WITHOUT_OPENCV_DOC()                                                         \
  if (!fs::exists(std::string(kDocData) + "/left01.jpg"))                                 \
  GTEST_SKIP() << kDocData << "/left01.jpg is absent: install opencv-doc "                \
               << "(scripts/install_deps.sh --test) to run the calibration on its images"

// Copies left*.jpg (and right*.jpg) of opencv-doc into dir/left (dir/right).
void CopyBoardImages(const TempDir& dir) {
  fs::create_directories(dir / "left");
  fs::create_directories(dir / "right");
  for (const auto& e : fs::directory_iterator(kDocData)) {
    const std::string name = e.path().filename().string();
    const bool numbered = name.size() == 10 && name.substr(6) == ".jpg";  // left01.jpg
    if (numbered && name.rfind("left", 0) == 0) fs::copy(e.path(), dir / ("left/" + name));
    if (name.size() == 11 && name.substr(7) == ".jpg" && name.rfind("right", 0) == 0) {
      fs::copy(e.path(), dir / ("right/" + name));
    }
  }
}

struct Cli {
  int status = -1;
  std::string out;
};

// `dala calibrate ARGS`: its exit code and all it printed.
Cli Calibrate(const std::string& args, const TempDir& dir) {
  const testing::DalaCliResult r = testing::RunDala("calibrate " + args, dir / "calibrate");
  return {r.status, r.log()};
}

TEST(CalibrateCli, MonoAgreesWithOpenCvsPublishedIntrinsicsAndRejectsBadViews) {
  SKIP_WITHOUT_OPENCV_DOC();
  TempDir dir;
  CopyBoardImages(dir);
  // A blurred copy of a view and an image without a board: rejected, saying why.
  cv::Mat blurred;
  cv::GaussianBlur(cv::imread(dir / "left/left01.jpg"), blurred, cv::Size(0, 0), 2.5);
  cv::imwrite(dir / "left/left15.jpg", blurred);
  cv::imwrite(dir / "left/left16.jpg", cv::Mat(480, 640, CV_8UC3, cv::Scalar::all(128)));
  const Cli cli = Calibrate((dir / "left") + " --out " + (dir / "cam.yml"), dir);
  ASSERT_EQ(cli.status, 0) << cli.out;
  std::cout << cli.out;
  EXPECT_THAT(cli.out, HasSubstr("rejected    left15.jpg: blurred"));
  EXPECT_THAT(cli.out, HasSubstr("rejected    left16.jpg: board not found"));
  EXPECT_THAT(cli.out, HasSubstr("views       13 used, 2 rejected, of 15"));
  EXPECT_THAT(cli.out, HasSubstr("view        left02.jpg: "));
  EXPECT_EQ(std::distance(fs::directory_iterator(dir / "cam_corners"), fs::directory_iterator()),
            13);

  // OpenCV's own result for these 13 views (fx = fy there: CALIB_FIX_ASPECT_RATIO).
  double fx = 535.9157, cx = 342.2832, cy = 235.5708, k1 = -0.26637;
  const std::string published = std::string(kDocData) + "/left_intrinsics.yml";
  if (fs::exists(published)) {
    const CameraCalibration p = ReadCameraCalibration(published);
    fx = p.cam0.fx, cx = p.cam0.cx, cy = p.cam0.cy, k1 = p.cam0.distortion[0];
  }
  const CameraCalibration c = ReadCameraCalibration(dir / "cam.yml");
  EXPECT_EQ(c.cam0.width, 640);
  EXPECT_NEAR(c.cam0.fx, fx, 0.005 * fx);
  EXPECT_NEAR(c.cam0.fy, fx, 0.005 * fx);
  EXPECT_NEAR(c.cam0.cx, cx, 1.0);
  EXPECT_NEAR(c.cam0.cy, cy, 1.0);
  EXPECT_NEAR(c.cam0.distortion[0], k1, 0.005);
  // dala run's path: undistortion maps from the file.
  EXPECT_FALSE(MakeRectification(c, /*stereo=*/false).rig.left.HasDistortion());

  // The fisheye model on the same views: the same focal length and principal point.
  const Cli fisheye = Calibrate((dir / "left") + " --model fisheye --calibration_format kalibr " +
                                    "--out " + (dir / "fisheye.yaml"),
                                dir);
  ASSERT_EQ(fisheye.status, 0) << fisheye.out;
  const CameraCalibration f = ReadCameraCalibration(dir / "fisheye.yaml");
  EXPECT_EQ(f.cam0.model, LensModel::kFisheye);
  EXPECT_NEAR(f.cam0.fx, fx, 0.01 * fx);
  EXPECT_NEAR(f.cam0.cx, cx, 2.0);
}

// The board pose of a view by PnP: T_c_board.
Pose BoardPose(const cv::Mat& image, const RawCamera& cam) {
  std::vector<cv::Point2f> corners;
  cv::Mat gray;
  cv::cvtColor(image, gray, cv::COLOR_BGR2GRAY);
  EXPECT_TRUE(cv::findChessboardCorners(gray, cv::Size(9, 6), corners));
  cv::cornerSubPix(gray, corners, cv::Size(11, 11), cv::Size(-1, -1),
                   cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 30, 0.01));
  std::vector<cv::Point3f> board;
  for (int r = 0; r < 6; ++r) {
    for (int c = 0; c < 9; ++c) board.emplace_back(c, r, 0);
  }
  cv::Mat rvec, tvec, R;
  cv::solvePnP(board, corners, cam.K(), cam.D(), rvec, tvec);
  cv::Rodrigues(rvec, R);
  Eigen::Matrix3d Re;
  for (int a = 0; a < 3; ++a) {
    for (int b = 0; b < 3; ++b) Re(a, b) = R.at<double>(a, b);
  }
  return MakePose(Re, Eigen::Vector3d(tvec.at<double>(0), tvec.at<double>(1), tvec.at<double>(2)));
}

TEST(CalibrateCli, StereoBaselineConsistentWithTheBoardPoses) {
  SKIP_WITHOUT_OPENCV_DOC();
  TempDir dir;
  CopyBoardImages(dir);
  const Cli cli = Calibrate((dir / "left") + " --right_folder " + (dir / "right") + " --out " +
                                (dir / "stereo.yml"),
                            dir);
  ASSERT_EQ(cli.status, 0) << cli.out;
  std::cout << cli.out;
  const CameraCalibration c = ReadCameraCalibration(dir / "stereo.yml");
  ASSERT_TRUE(c.cam1.has_value());
  const Eigen::Vector3d t = c.T_c1_c0.translation();
  // OpenCV's stereo_calib sample on these images: the right camera ~3.3 squares to the right
  // (T_c1_c0 translation ~(-3.3, 0, 0)).
  EXPECT_LT(t.x(), -3.0);
  EXPECT_GT(t.x(), -3.7);
  EXPECT_LT(std::abs(t.y()) + std::abs(t.z()), 0.2);
  // Each pair's board poses give T_c1_c0 = T_c1_board T_c0_board^-1: their median baseline
  // agrees with the stereo calibration's to 2 %.
  std::vector<double> baselines;
  for (const auto& e : fs::directory_iterator(dir / "left")) {
    const std::string name = e.path().filename().string();
    const Pose T_c0_b = BoardPose(cv::imread(e.path().string()), c.cam0);
    const Pose T_c1_b = BoardPose(cv::imread(dir / ("right/right" + name.substr(4))), *c.cam1);
    baselines.push_back((T_c1_b * T_c0_b.inverse()).translation().norm());
  }
  std::sort(baselines.begin(), baselines.end());
  const double median = baselines[baselines.size() / 2];
  std::cout << "[ measured ] stereo baseline " << t.norm() << " squares, median of the pairs' "
            << "board poses " << median << std::endl;
  EXPECT_NEAR(t.norm(), median, 0.02 * median);
  // dala run's path: the pair is rectified at open.
  const Rectification r = MakeRectification(c, /*stereo=*/true);
  EXPECT_NEAR(r.rig.baseline, t.norm(), 1e-6);
}

TEST(CalibrateCli, FromAVideoOfTheBoard) {
  SKIP_WITHOUT_OPENCV_DOC();
  TempDir dir;
  CopyBoardImages(dir);
  // The 13 views as the frames of an MJPEG video, each twice: --frame_step 2 takes one of each.
  {
    cv::VideoWriter writer(dir / "board.avi", cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 5.0,
                           cv::Size(640, 480));
    ASSERT_TRUE(writer.isOpened());
    std::vector<std::string> files;
    for (const auto& e : fs::directory_iterator(dir / "left")) files.push_back(e.path().string());
    std::sort(files.begin(), files.end());
    for (const std::string& f : files) {
      const cv::Mat image = cv::imread(f);
      writer.write(image);
      writer.write(image);
    }
  }
  const Cli cli =
      Calibrate((dir / "board.avi") + " --frame_step 2 --out " + (dir / "video.yml"), dir);
  ASSERT_EQ(cli.status, 0) << cli.out;
  EXPECT_THAT(cli.out, HasSubstr("views       13 used, 0 rejected, of 13"));
  const CameraCalibration c = ReadCameraCalibration(dir / "video.yml");
  EXPECT_NEAR(c.cam0.fx, 535.9, 0.01 * 535.9);  // As from the images (lossy frames).
  EXPECT_NEAR(c.cam0.cx, 342.3, 2.0);
}

TEST(CalibrateCli, TooFewViewsIsAnErrorSayingWhatToDo) {
  TempDir dir;
  fs::create_directories(dir / "imgs");
  cv::imwrite(dir / "imgs/a.png", cv::Mat(48, 64, CV_8UC1, cv::Scalar(50)));
  const Cli cli = Calibrate((dir / "imgs") + " --out " + (dir / "cam.yml"), dir);
  EXPECT_EQ(cli.status, 2);
  EXPECT_THAT(cli.out, HasSubstr("a.png: board not found"));
  EXPECT_THAT(cli.out, HasSubstr("too few views with the board (0 of 1, 4 needed)"));
  EXPECT_FALSE(fs::exists(dir / "cam.yml"));
}

}  // namespace
}  // namespace dala
