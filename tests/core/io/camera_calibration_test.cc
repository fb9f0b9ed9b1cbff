// The calibration files people already have (one test file per format in tests/core/io/data/),
// and the rectification built from them, checked pixel by pixel against OpenCV's own projection.
#include "core/io/camera_calibration.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "tests/core/io/dataset_fixtures.h"
#include "tests/test_util.h"

namespace dala {
namespace {

using testing::ErrorOf;
using ::testing::HasSubstr;
using testing::TempDir;
using testing::WriteText;

std::string Data(const std::string& name) {
  return std::string(DALA_SOURCE_DIR) + "/tests/core/io/data/" + name;
}

TEST(CameraCalibration, OpenCvCalibrationOutput) {
  const CameraCalibration c = ReadCameraCalibration(Data("opencv_calibration.yml"));
  EXPECT_EQ(c.format, CalibrationFormat::kOpenCv);
  EXPECT_EQ(c.cam0.width, 640);
  EXPECT_EQ(c.cam0.height, 480);
  EXPECT_NEAR(c.cam0.fx, 535.91573396163199, 1e-9);
  EXPECT_NEAR(c.cam0.cy, 235.57082909788173, 1e-9);
  EXPECT_EQ(c.cam0.model, LensModel::kRadtan);
  EXPECT_NEAR(c.cam0.distortion[4], 0.23839153080878486, 1e-12);
  EXPECT_FALSE(c.is_stereo());
}

TEST(CameraCalibration, OpenCvDocsLeftIntrinsics) {
  const std::string path = "/usr/share/doc/opencv-doc/examples/data/left_intrinsics.yml";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << path << " absent (apt install opencv-doc)";
  const CameraCalibration c = ReadCameraCalibration(path);
  EXPECT_EQ(c.format, CalibrationFormat::kOpenCv);
  EXPECT_NEAR(c.cam0.fx, 535.9157, 1e-3);
}

TEST(CameraCalibration, OpenCvWrittenByFileStorageFisheyeAndStereo) {
  TempDir dir;
  const std::string path = dir / "stereo.yml";
  {
    cv::FileStorage fs(path, cv::FileStorage::WRITE);
    fs << "image_width" << 320 << "image_height" << 240 << "fisheye_model" << 1;
    fs << "camera_matrix" << cv::Mat(cv::Matx33d(200, 0, 160, 0, 201, 120, 0, 0, 1));
    fs << "distortion_coefficients" << cv::Mat(cv::Matx14d(0.01, -0.002, 0.001, 0));
    fs << "camera_matrix_right" << cv::Mat(cv::Matx33d(202, 0, 161, 0, 202, 119, 0, 0, 1));
    fs << "distortion_coefficients_right" << cv::Mat(cv::Matx14d(0.02, 0, 0, 0));
    fs << "R" << cv::Mat(cv::Matx33d::eye()) << "T" << cv::Mat(cv::Vec3d(-0.1, 0, 0));
  }
  const CameraCalibration c = ReadCameraCalibration(path);
  EXPECT_EQ(c.format, CalibrationFormat::kOpenCv);
  EXPECT_EQ(c.cam0.model, LensModel::kFisheye);
  ASSERT_TRUE(c.cam1.has_value());
  EXPECT_DOUBLE_EQ(c.cam1->fx, 202);
  EXPECT_NEAR(c.T_c1_c0.translation().x(), -0.1, 1e-12);
}

TEST(CameraCalibration, RosCameraInfo) {
  const CameraCalibration c = ReadCameraCalibration(Data("ros_camera_info.yaml"));
  EXPECT_EQ(c.format, CalibrationFormat::kRos);
  EXPECT_EQ(c.cam0.width, 752);
  EXPECT_DOUBLE_EQ(c.cam0.fy, 457.296);
  EXPECT_DOUBLE_EQ(c.cam0.cx, 367.215);
  EXPECT_DOUBLE_EQ(c.cam0.distortion[0], -0.28340811);
}

TEST(CameraCalibration, KalibrRadtanAndEquidistantPairs) {
  const CameraCalibration r = ReadCameraCalibration(Data("kalibr_camchain_radtan.yaml"));
  EXPECT_EQ(r.format, CalibrationFormat::kKalibr);
  EXPECT_EQ(r.cam0.model, LensModel::kRadtan);
  ASSERT_TRUE(r.cam1.has_value());
  EXPECT_DOUBLE_EQ(r.cam1->fx, 457.587);
  EXPECT_NEAR(r.T_c1_c0.translation().x(), -0.1100738081272, 1e-12);
  const CameraCalibration e = ReadCameraCalibration(Data("kalibr_camchain_equi.yaml"));
  EXPECT_EQ(e.cam0.model, LensModel::kFisheye);
  EXPECT_EQ(e.cam1->model, LensModel::kFisheye);
  EXPECT_EQ(e.cam0.width, 512);
}

TEST(CameraCalibration, DalaOwnRectifiedPair) {
  const CameraCalibration c = ReadCameraCalibration(Data("dala_calibration.yaml"));
  EXPECT_EQ(c.format, CalibrationFormat::kDala);
  EXPECT_DOUBLE_EQ(c.rectified_baseline, 0.537);
  const Rectification r = MakeRectification(c, /*stereo=*/true);
  EXPECT_TRUE(r.left_map1.empty());
  EXPECT_DOUBLE_EQ(r.rig.baseline, 0.537);
  EXPECT_DOUBLE_EQ(r.rig.left.fx, 707.0912);
}

TEST(CameraCalibration, ErrorsNameTheFileAndTheFix) {
  TempDir dir;
  const std::string path = dir / "cam.yaml";
  EXPECT_THAT(ErrorOf([&] { ReadCameraCalibration(path); }), HasSubstr("missing calibration"));
  WriteText(path,
            "image_width: 640\nimage_height: 480\ncamera_matrix:\n  rows: 3\n  cols: 3\n"
            "  data: [500, 0, 320, 0, 500, 240, 0, 0, 1]\ndistortion_model: rational_polynomial\n"
            "distortion_coefficients:\n  rows: 1\n  cols: 8\n  data: [0, 0, 0, 0, 0, 0, 0, 0]\n");
  const std::string unknown = ErrorOf([&] { ReadCameraCalibration(path); });
  EXPECT_THAT(unknown, HasSubstr(path));
  EXPECT_THAT(unknown, HasSubstr("unknown distortion model 'rational_polynomial'"));
  EXPECT_THAT(unknown, HasSubstr("equidistant"));
  WriteText(path, "foo: 1\n");
  EXPECT_THAT(ErrorOf([&] { ReadCameraCalibration(path); }),
              HasSubstr("not a calibration file dala knows"));
  WriteText(path, "cam0:\n  camera_model: omni\n  intrinsics: [1, 2, 3, 4]\n");
  EXPECT_THAT(ErrorOf([&] { ReadCameraCalibration(path); }), HasSubstr("'omni' is not supported"));
  // A monocular calibration for a stereo pair.
  EXPECT_THAT(ErrorOf([&] {
                MakeRectification(ReadCameraCalibration(Data("ros_camera_info.yaml")), true);
              }),
              HasSubstr("stereo pair"));
}

// The remap tables at an integer pixel (u, v) of the output image: the raw pixel they sample.
cv::Point2d MapAt(const cv::Mat& map1, const cv::Mat& map2, int u, int v) {
  cv::Mat fx, fy;
  cv::convertMaps(map1, map2, fx, fy, CV_32FC1);
  return {fx.at<float>(v, u), fy.at<float>(v, u)};
}

cv::Point2d ProjectRaw(const RawCamera& cam, const Eigen::Vector3d& p_c) {
  std::vector<cv::Point3d> in = {{p_c.x(), p_c.y(), p_c.z()}};
  std::vector<cv::Point2d> out;
  if (cam.model == LensModel::kFisheye) {
    cv::fisheye::projectPoints(in, out, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), cam.K(), cam.D());
  } else {
    cv::projectPoints(in, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), cam.K(), cam.D(), out);
  }
  return out[0];
}

// Round trip: a point seen at an integer pixel of the rectified left image, and at an integer
// disparity (same row) in the rectified right one, is where OpenCV projects it in the raw images.
void ExpectStereoRoundTrip(const CameraCalibration& c) {
  const Rectification r = MakeRectification(c, /*stereo=*/true);
  const PinholeCamera& k = r.rig.left;
  EXPECT_GT(r.rig.baseline, 0.09);
  for (const auto& [u, v, d] : {std::tuple{100, 120, 10}, std::tuple{300, 200, 25},
                                std::tuple{200, 300, 5}}) {
    const double z = k.fx * r.rig.baseline / d;
    const Eigen::Vector3d p_rect((u - k.cx) / k.fx * z, (v - k.cy) / k.fy * z, z);
    const Eigen::Vector3d p_c0 = r.T_c0_c0rect * p_rect;
    const cv::Point2d raw0 = ProjectRaw(c.cam0, p_c0);
    const cv::Point2d m0 = MapAt(r.left_map1, r.left_map2, u, v);
    EXPECT_NEAR(m0.x, raw0.x, 0.05) << u << "," << v;
    EXPECT_NEAR(m0.y, raw0.y, 0.05) << u << "," << v;
    const cv::Point2d raw1 = ProjectRaw(*c.cam1, c.T_c1_c0 * p_c0);
    const cv::Point2d m1 = MapAt(r.right_map1, r.right_map2, u - d, v);
    EXPECT_NEAR(m1.x, raw1.x, 0.05) << u << "," << v;
    EXPECT_NEAR(m1.y, raw1.y, 0.05) << u << "," << v;
  }
}

TEST(Rectification, RadtanStereoRoundTripAgainstOpenCv) {
  ExpectStereoRoundTrip(ReadCameraCalibration(Data("kalibr_camchain_radtan.yaml")));
}

TEST(Rectification, FisheyeStereoRoundTripAgainstOpenCv) {
  ExpectStereoRoundTrip(ReadCameraCalibration(Data("kalibr_camchain_equi.yaml")));
}

TEST(Rectification, MonoUndistortionRoundTripBothModels) {
  for (const char* file : {"ros_camera_info.yaml", "kalibr_camchain_equi.yaml"}) {
    const CameraCalibration c = ReadCameraCalibration(Data(file));
    const Rectification r = MakeRectification(c, /*stereo=*/false);
    EXPECT_EQ(r.rig.baseline, 0);
    EXPECT_FALSE(r.rig.left.HasDistortion());
    EXPECT_EQ(r.rig.left.width, c.cam0.width);
    for (const auto& [u, v] : {std::pair{50, 60}, std::pair{250, 240}, std::pair{400, 100}}) {
      const Eigen::Vector3d ray = r.rig.left.Unproject(Eigen::Vector2d(u, v));
      const cv::Point2d raw = ProjectRaw(c.cam0, ray);
      const cv::Point2d m = MapAt(r.left_map1, r.left_map2, u, v);
      EXPECT_NEAR(m.x, raw.x, 0.05) << file << " " << u << "," << v;
      EXPECT_NEAR(m.y, raw.y, 0.05) << file << " " << u << "," << v;
    }
  }
}

}  // namespace
}  // namespace dala
