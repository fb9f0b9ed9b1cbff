#include "core/io/euroc_dataset.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <iostream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "core/error.h"
#include "core/io/dataset.h"
#include "core/io/trajectory_io.h"
#include "tests/core/io/dataset_fixtures.h"
#include "tests/test_util.h"

namespace dala {
namespace {

using testing::ErrorOf;
using ::testing::HasSubstr;
using testing::RandomImage;
using testing::TempDir;
using testing::WriteText;

constexpr int64_t kT0 = 1403715273262142976;
// ~20 Hz; a multiple of 256 ns so that the stamps survive the double the ground-truth reader
// parses them through (exact interpolation checks below).
constexpr int64_t kDt = 50000128;

std::string SensorYaml(double tx, const std::string& model = "radial-tangential") {
  return "%YAML:1.0\nsensor_type: camera\nT_BS:\n  cols: 4\n  rows: 4\n  data: [1, 0, 0, " +
         std::to_string(tx) +
         ", 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]\nrate_hz: 20\nresolution: [64, 48]\n"
         "camera_model: pinhole\nintrinsics: [60.0, 60.0, 32.0, 24.0]\n"
         "distortion_model: " +
         model + "\ndistortion_coefficients: [-0.1, 0.01, 0.0, 0.0]\n";
}

// A 4-frame EuRoC folder (mav0/...), cam1 0.1 m to the right of cam0 with parallel axes. Ground
// truth covers frames 1 to 3 only: body at x = 0 at frame 1's time, x = 1 at frame 3's.
void WriteEurocFolder(const std::string& folder, bool stereo = true) {
  for (int cam = 0; cam < (stereo ? 2 : 1); ++cam) {
    const std::string dir = folder + "/mav0/cam" + std::to_string(cam);
    std::filesystem::create_directories(dir + "/data");
    WriteText(dir + "/sensor.yaml", SensorYaml(cam == 0 ? 0.0 : 0.1));
    std::string csv = "#timestamp [ns],filename\n";
    for (int i = 0; i < 4; ++i) {
      const std::string name = std::to_string(kT0 + i * kDt) + ".png";
      cv::imwrite(dir + "/data/" + name, RandomImage(64, 48, 100 * cam + i));
      csv += std::to_string(kT0 + i * kDt) + "," + name + "\n";
    }
    WriteText(dir + "/data.csv", csv);
  }
  WriteText(folder + "/mav0/state_groundtruth_estimate0/data.csv",
            "#timestamp, p_RS_R_x [m], p_RS_R_y [m], p_RS_R_z [m], q_RS_w [], q_RS_x [], "
            "q_RS_y [], q_RS_z []\n" +
                std::to_string(kT0 + kDt) + ",0,0,0,1,0,0,0\n" + std::to_string(kT0 + 3 * kDt) +
                ",1,0,0,1,0,0,0\n");
}

TEST(EurocDataset, ReadsStereoFixtureWithGroundTruthInterpolation) {
  TempDir dir;
  WriteEurocFolder(dir.path());
  EXPECT_EQ(DetectDatasetFormat(dir.path()), DatasetFormat::kEuroc);
  EXPECT_EQ(DetectDatasetFormat(dir / "mav0"), DatasetFormat::kEuroc);
  auto dataset = OpenDataset(dir.path());
  EXPECT_EQ(dataset->format(), DatasetFormat::kEuroc);
  EXPECT_TRUE(dataset->is_stereo());
  EXPECT_EQ(dataset->size(), 4u);
  const StereoRig& rig = dataset->rig();
  EXPECT_FALSE(rig.left.HasDistortion());
  EXPECT_NEAR(rig.baseline, 0.1, 1e-9);
  EXPECT_EQ(rig.left.width, 64);
  EXPECT_EQ(rig.left.height, 48);
  EXPECT_NEAR(rig.left.fx, 60.0, 3.0);
  ASSERT_TRUE(dataset->ground_truth().has_value());
  ASSERT_EQ(dataset->ground_truth()->size(), 3u);
  Frame frame;
  std::vector<std::optional<double>> gt_x;
  while (dataset->Next(&frame)) {
    EXPECT_EQ(frame.t_ns, kT0 + frame.id.value * kDt);
    EXPECT_EQ(frame.left.size(), cv::Size(64, 48));
    EXPECT_EQ(frame.right.size(), cv::Size(64, 48));
    gt_x.push_back(frame.T_w_c0_gt ? std::optional<double>(frame.T_w_c0_gt->translation().x())
                                   : std::nullopt);
  }
  ASSERT_EQ(gt_x.size(), 4u);
  EXPECT_FALSE(gt_x[0].has_value());  // Before the ground truth.
  ASSERT_TRUE(gt_x[1].has_value());
  EXPECT_NEAR(*gt_x[1], 0.0, 1e-9);
  ASSERT_TRUE(gt_x[2].has_value());
  EXPECT_NEAR(*gt_x[2], 0.5, 1e-9);  // Halfway between the two samples.
  ASSERT_TRUE(gt_x[3].has_value());
  EXPECT_NEAR(*gt_x[3], 1.0, 1e-9);  // The last sample.
}

TEST(EurocDataset, GroundTruthGapLimit) {
  TempDir dir;
  WriteEurocFolder(dir.path());
  DatasetOptions options;
  options.max_ground_truth_gap_s = 0.05;  // The samples are 0.1 s apart.
  auto dataset = OpenDataset(dir.path(), options);
  ASSERT_TRUE(dataset->ground_truth().has_value());
  ASSERT_EQ(dataset->ground_truth()->size(), 2u);  // Frames 1 and 3, on samples; not 2.
  EXPECT_EQ(dataset->ground_truth()->poses[1].t_ns, kT0 + 3 * kDt);
}

TEST(EurocDataset, MonoUndistortsCam0) {
  TempDir dir;
  WriteEurocFolder(dir.path(), /*stereo=*/false);
  auto dataset = OpenDataset(dir.path());
  EXPECT_FALSE(dataset->is_stereo());
  EXPECT_EQ(dataset->rig().baseline, 0);
  EXPECT_FALSE(dataset->rig().left.HasDistortion());
  Frame frame;
  ASSERT_TRUE(dataset->Next(&frame));
  EXPECT_TRUE(frame.right.empty());
  EXPECT_GT(cv::norm(frame.left, RandomImage(64, 48, 0), cv::NORM_INF), 0);  // Remapped.
}

TEST(EurocDataset, UnpairedImagesAreSkipped) {
  TempDir dir;
  WriteEurocFolder(dir.path());
  // cam1 lacks frame 2.
  const std::string csv1 = dir / "mav0/cam1/data.csv";
  WriteText(csv1, std::to_string(kT0) + "," + std::to_string(kT0) + ".png\n" +
                      std::to_string(kT0 + kDt) + "," + std::to_string(kT0 + kDt) + ".png\n" +
                      std::to_string(kT0 + 3 * kDt) + "," + std::to_string(kT0 + 3 * kDt) +
                      ".png\n");
  auto dataset = OpenDataset(dir.path());
  EXPECT_EQ(dataset->size(), 3u);
  Frame frame;
  std::vector<int64_t> times;
  while (dataset->Next(&frame)) times.push_back(frame.t_ns);
  EXPECT_EQ(times, (std::vector<int64_t>{kT0, kT0 + kDt, kT0 + 3 * kDt}));
}

TEST(EurocDataset, Errors) {
  TempDir dir;
  const auto fresh = [&](const std::string& name) {
    WriteEurocFolder(dir / name);
    return dir / name;
  };
  {
    const std::string seq = fresh("order");
    const std::string t0 = std::to_string(kT0), t1 = std::to_string(kT0 + kDt);
    WriteText(seq + "/mav0/cam0/data.csv",
              "#h\n" + t1 + "," + t1 + ".png\n" + t0 + "," + t0 + ".png\n");
    EXPECT_THAT(
        ErrorOf([&] { OpenDataset(seq); }),
        HasSubstr("cam0/data.csv:3: timestamp " + std::to_string(kT0) + " does not increase"));
  }
  {
    const std::string seq = fresh("missing_image");
    std::filesystem::remove(seq + "/mav0/cam1/data/" + std::to_string(kT0 + kDt) + ".png");
    EXPECT_THAT(ErrorOf([&] { OpenDataset(seq); }), HasSubstr("cam1/data.csv:3: missing image"));
    // Not in the range to run: not checked. Allowed: that frame is a FrameError when read.
    DatasetOptions options;
    options.max_frames = 1;
    EXPECT_NO_THROW(OpenDataset(seq, options));
    options.max_frames = 0;
    options.allow_missing_images = true;
    auto dataset = OpenDataset(seq, options);
    Frame frame;
    ASSERT_TRUE(dataset->Next(&frame));
    EXPECT_THAT(ErrorOf([&] { dataset->Next(&frame); }), HasSubstr("missing image"));
    ASSERT_TRUE(dataset->Next(&frame));
    EXPECT_EQ(frame.id.value, 2);
  }
  {
    // No cam1 image pairs with a cam0 one: the message names the `dala run` flag that exists.
    const std::string seq = fresh("unpaired");
    WriteText(seq + "/mav0/cam1/data.csv", "#h\n1," + std::to_string(kT0) + ".png\n");
    const std::string msg = ErrorOf([&] { OpenDataset(seq); });
    EXPECT_THAT(msg, HasSubstr("no cam0 image has a cam1 image"));
    EXPECT_THAT(msg, HasSubstr("--mode mono"));
    EXPECT_THAT(msg, ::testing::Not(HasSubstr("--mono)")));
  }
  {
    const std::string seq = fresh("bad_stamp");
    WriteText(seq + "/mav0/cam0/data.csv", "12.5e3,a.png\n");
    EXPECT_THAT(ErrorOf([&] { OpenDataset(seq); }), HasSubstr("integer nanoseconds"));
  }
  {
    const std::string seq = fresh("no_intrinsics");
    std::string yaml = SensorYaml(0.0);
    yaml.replace(yaml.find("intrinsics"), 10, "intrinsic");
    WriteText(seq + "/mav0/cam0/sensor.yaml", yaml);
    EXPECT_THAT(ErrorOf([&] { OpenDataset(seq); }),
                HasSubstr("cam0/sensor.yaml: 'intrinsics': missing"));
  }
  {
    const std::string seq = fresh("equidistant");
    WriteText(seq + "/mav0/cam1/sensor.yaml", SensorYaml(0.1, "equidistant"));
    EXPECT_THAT(ErrorOf([&] { OpenDataset(seq); }), HasSubstr("'equidistant' is not supported"));
  }
  {
    const std::string seq = fresh("left_of");
    WriteText(seq + "/mav0/cam1/sensor.yaml", SensorYaml(-0.1));
    EXPECT_THAT(ErrorOf([&] { OpenDataset(seq); }), HasSubstr("not to the right of cam0"));
  }
  {
    const std::string seq = fresh("wrong_size");
    cv::imwrite(seq + "/mav0/cam0/data/" + std::to_string(kT0) + ".png", RandomImage(32, 48, 0));
    EXPECT_THAT(ErrorOf([&] { OpenDataset(seq); }),
                HasSubstr("is 32x48, expected 64x48 (from " + seq + "/mav0/cam0/sensor.yaml"));
  }
  {
    const std::string seq = fresh("override");
    DatasetOptions options;
    options.calibration_yaml = dir / "calib.yaml";
    EXPECT_THAT(ErrorOf([&] { OpenDataset(seq, options); }),
                HasSubstr("cannot be used with EuRoC"));
  }
}

// Sub-pixel (parabola) peak of a 1-D score profile around its maximum index.
double ParabolaPeak(double left, double centre, double right) {
  const double denom = left - 2 * centre + right;
  return std::abs(denom) < 1e-12 ? 0.0 : 0.5 * (left - right) / denom;
}

// For strong corners of `left`, finds the patch in `right` (disparity 0..120 px, rows +-12) and
// returns the vertical offsets (right - left) of the confident matches.
std::vector<double> VerticalOffsets(const cv::Mat& left, const cv::Mat& right,
                                    std::vector<double>* disparities) {
  std::vector<cv::Point2f> corners;
  cv::goodFeaturesToTrack(left, corners, 60, 0.05, 20.0, cv::Mat(), 5);
  const int half = 10, search_y = 12, max_d = 120;
  std::vector<double> dys;
  for (const cv::Point2f& c : corners) {
    const int x = cvRound(c.x), y = cvRound(c.y);
    if (x - half - max_d < 0 || x + half >= left.cols || y - half - search_y < 0 ||
        y + half + search_y >= left.rows) {
      continue;
    }
    const cv::Mat patch = left(cv::Rect(x - half, y - half, 2 * half + 1, 2 * half + 1));
    const cv::Rect region(x - half - max_d, y - half - search_y, 2 * half + 1 + max_d,
                          2 * half + 1 + 2 * search_y);
    cv::Mat score;
    cv::matchTemplate(right(region), patch, score, cv::TM_CCOEFF_NORMED);
    double best;
    cv::Point loc;
    cv::minMaxLoc(score, nullptr, &best, nullptr, &loc);
    if (best < 0.9 || loc.y == 0 || loc.y == score.rows - 1 || loc.x == 0 ||
        loc.x == score.cols - 1) {
      continue;
    }
    const double sub_y =
        ParabolaPeak(score.at<float>(loc.y - 1, loc.x), score.at<float>(loc.y, loc.x),
                     score.at<float>(loc.y + 1, loc.x));
    dys.push_back(loc.y + sub_y - search_y);
    if (disparities) disparities->push_back(max_d - loc.x);
  }
  return dys;
}

double Median(std::vector<double> v) {
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

TEST(EurocDataset, RealV101RectifiedRowsAlign) {
  DALA_SKIP_WITHOUT_SHARED_DATA("euroc_v101_micro");
  const std::string folder = testing::SharedDataDir() + "/euroc_v101_micro";
  EXPECT_EQ(DetectDatasetFormat(folder), DatasetFormat::kEuroc);
  auto dataset = OpenDataset(folder);
  EXPECT_EQ(dataset->size(), 20u);
  ASSERT_TRUE(dataset->is_stereo());
  const StereoRig& rig = dataset->rig();
  EXPECT_EQ(rig.left.width, 752);
  EXPECT_EQ(rig.left.height, 480);
  EXPECT_NEAR(rig.baseline, 0.110, 0.005);
  EXPECT_GT(rig.left.fx, 400);
  EXPECT_LT(rig.left.fx, 500);
  ASSERT_TRUE(dataset->ground_truth().has_value());
  EXPECT_EQ(dataset->ground_truth()->size(), 20u);

  Frame frame;
  ASSERT_TRUE(dataset->Next(&frame));
  EXPECT_EQ(frame.t_ns, 1403715273262142976);
  ASSERT_EQ(frame.left.size(), cv::Size(752, 480));
  ASSERT_EQ(frame.right.size(), cv::Size(752, 480));
  std::vector<double> disparities;
  const std::vector<double> dy = VerticalOffsets(frame.left, frame.right, &disparities);
  ASSERT_GE(dy.size(), 10u) << "too few confident matches to judge the rectification";
  int aligned = 0;
  for (double d : dy) aligned += std::abs(d) < 1.0;
  EXPECT_GE(aligned, static_cast<int>(0.9 * dy.size()));
  EXPECT_LT(std::abs(Median(dy)), 0.5);
  EXPECT_GT(Median(disparities), 0.0);  // Right camera at +x: points move left.
  std::cout << "[ measured ] rectified: " << dy.size() << " matches, " << aligned
            << " with |dy| < 1 px, median dy " << Median(dy) << " px, baseline " << rig.baseline
            << " m, fx " << rig.left.fx << "\n";

  // The raw images are not row-aligned (cy differs by ~7 px and the lenses distort): without
  // rectification the same check fails, so it does test the rectification.
  const std::string raw = folder + "/mav0/cam%d/data/1403715273262142976.png";
  const cv::Mat raw0 = cv::imread(cv::format(raw.c_str(), 0), cv::IMREAD_GRAYSCALE);
  const cv::Mat raw1 = cv::imread(cv::format(raw.c_str(), 1), cv::IMREAD_GRAYSCALE);
  const std::vector<double> raw_dy = VerticalOffsets(raw0, raw1, nullptr);
  ASSERT_GE(raw_dy.size(), 5u);
  EXPECT_GT(std::abs(Median(raw_dy)), 2.0);
  std::cout << "[ measured ] raw: median dy " << Median(raw_dy) << " px\n";

  // Ground truth: the rectified camera sits where cam0 is on the body (rectification only
  // rotates), and its z axis (forward) is within a few degrees of cam0's.
  const Pose& T_w_c0rect = *frame.T_w_c0_gt;
  const Trajectory T_w_b = ReadTrajectory(folder + "/mav0/state_groundtruth_estimate0/data.csv");
  const EurocCamera cam0 = ReadEurocSensorYaml(folder + "/mav0/cam0/sensor.yaml");
  const Pose T_w_c0 = T_w_b.poses[0].T_w_c * cam0.T_b_c;
  EXPECT_LT((T_w_c0rect.translation() - T_w_c0.translation()).norm(), 1e-9);
  const double angle =
      std::acos(std::clamp(T_w_c0rect.linear().col(2).dot(T_w_c0.linear().col(2)), -1.0, 1.0));
  EXPECT_LT(angle, 3.0 * M_PI / 180.0);
}

}  // namespace
}  // namespace dala
