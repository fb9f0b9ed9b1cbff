#include "core/io/kitti_dataset.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>

#include "core/error.h"
#include "core/io/dataset.h"
#include "tests/core/io/dataset_fixtures.h"
#include "tests/test_util.h"

namespace dala {
namespace {

using testing::ErrorOf;
using ::testing::HasSubstr;
using testing::KittiFixture;
using testing::KittiName;
using testing::RandomImage;
using testing::TempDir;
using testing::WriteKittiFolder;
using testing::WriteText;

double MaxAbsDiff(const cv::Mat& a, const cv::Mat& b) { return cv::norm(a, b, cv::NORM_INF); }

// odometry.txt (TUM, as `dala synth --odometry` writes it): one pose per image time, in
// Frame::T_w_odom; absent file: no odometry.
TEST(KittiDataset, ReadsOdometry) {
  TempDir dir;
  const std::string seq = dir / "seq";
  WriteKittiFolder(seq, KittiFixture());
  {
    auto dataset = OpenDataset(seq);
    Frame frame;
    ASSERT_TRUE(dataset->Next(&frame));
    EXPECT_FALSE(frame.T_w_odom.has_value());
  }
  // A sample before the first image is skipped; times match to the rounding of the file.
  WriteText(seq + "/odometry.txt",
            "-0.1 9 9 9 0 0 0 1\n0 0 0 0 0 0 0 1\n0.1000000004 1 0 0 0 0 0 1\n"
            "0.2 2 0 0 0 0 0.7071067811865476 0.7071067811865476\n0.3 3 0 0 0 0 0 1\n");
  DatasetOptions mono;
  mono.force_mono = true;
  auto dataset = OpenDataset(seq, mono);
  Frame frame;
  for (int i = 0; i < 4; ++i) {
    ASSERT_TRUE(dataset->Next(&frame));
    ASSERT_TRUE(frame.T_w_odom.has_value()) << i;
    EXPECT_NEAR(frame.T_w_odom->translation().x(), i, 1e-12);
  }
  EXPECT_NEAR(frame.T_w_odom->linear()(0, 0), 1.0, 1e-12);
}

TEST(KittiDataset, ReadsStereoFixture) {
  TempDir dir;
  const std::string seq = dir / "seq";
  WriteKittiFolder(seq, KittiFixture());
  EXPECT_EQ(DetectDatasetFormat(seq), DatasetFormat::kKitti);
  auto dataset = OpenDataset(seq);
  EXPECT_EQ(dataset->format(), DatasetFormat::kKitti);
  EXPECT_EQ(dataset->path(), seq);
  EXPECT_TRUE(dataset->is_stereo());
  EXPECT_EQ(dataset->size(), 4u);
  const StereoRig& rig = dataset->rig();
  EXPECT_EQ(rig.left.width, 64);
  EXPECT_EQ(rig.left.height, 48);
  EXPECT_DOUBLE_EQ(rig.left.fx, 100);
  EXPECT_DOUBLE_EQ(rig.left.cx, 31.5);
  EXPECT_DOUBLE_EQ(rig.left.cy, 23.5);
  EXPECT_NEAR(rig.baseline, 0.5, 1e-12);
  ASSERT_TRUE(dataset->ground_truth().has_value());
  EXPECT_EQ(dataset->ground_truth()->size(), 4u);
  for (int pass = 0; pass < 2; ++pass) {
    Frame frame;
    for (int i = 0; i < 4; ++i) {
      ASSERT_TRUE(dataset->Next(&frame));
      EXPECT_EQ(frame.id.value, i);
      EXPECT_EQ(frame.t_ns, i * 100000000LL);
      ASSERT_TRUE(frame.is_stereo());
      EXPECT_EQ(frame.left.type(), CV_8UC1);
      EXPECT_EQ(MaxAbsDiff(frame.left, RandomImage(64, 48, i)), 0);
      EXPECT_EQ(MaxAbsDiff(frame.right, RandomImage(64, 48, 1000 + i)), 0);
      ASSERT_TRUE(frame.T_w_c0_gt.has_value());
      EXPECT_NEAR(frame.T_w_c0_gt->translation().z(), i, 1e-12);
      EXPECT_EQ(dataset->ground_truth()->poses[i].t_ns, frame.t_ns);
    }
    EXPECT_FALSE(dataset->Next(&frame));
    dataset->Rewind();
  }
}

TEST(KittiDataset, MonoWhenNoRightImagesOrForced) {
  TempDir dir;
  KittiFixture fixture;
  fixture.stereo = false;
  fixture.poses = false;
  WriteKittiFolder(dir / "mono", fixture);
  auto mono = OpenDataset(dir / "mono");
  EXPECT_FALSE(mono->is_stereo());
  EXPECT_EQ(mono->rig().baseline, 0.0);
  EXPECT_FALSE(mono->ground_truth().has_value());
  Frame frame;
  ASSERT_TRUE(mono->Next(&frame));
  EXPECT_TRUE(frame.right.empty());
  EXPECT_FALSE(frame.T_w_c0_gt.has_value());

  WriteKittiFolder(dir / "stereo", KittiFixture());
  DatasetOptions options;
  options.force_mono = true;
  auto forced = OpenDataset(dir / "stereo", options);
  EXPECT_FALSE(forced->is_stereo());
  ASSERT_TRUE(forced->Next(&frame));
  EXPECT_TRUE(frame.right.empty());
}

TEST(KittiDataset, FirstFrameAndMaxFrames) {
  TempDir dir;
  WriteKittiFolder(dir.path(), KittiFixture());
  DatasetOptions options;
  options.first_frame = 1;
  options.max_frames = 2;
  auto dataset = OpenDataset(dir.path(), options);
  EXPECT_EQ(dataset->size(), 2u);
  ASSERT_EQ(dataset->ground_truth()->size(), 2u);
  EXPECT_EQ(dataset->ground_truth()->poses[0].t_ns, 100000000LL);
  Frame frame;
  ASSERT_TRUE(dataset->Next(&frame));
  EXPECT_EQ(frame.id.value, 1);
  EXPECT_EQ(MaxAbsDiff(frame.left, RandomImage(64, 48, 1)), 0);
  ASSERT_TRUE(dataset->Next(&frame));
  EXPECT_EQ(frame.id.value, 2);
  EXPECT_FALSE(dataset->Next(&frame));
  options.first_frame = 4;
  EXPECT_THAT(ErrorOf([&] { OpenDataset(dir.path(), options); }), HasSubstr("past the end"));
  options.first_frame = -1;
  EXPECT_THAT(ErrorOf([&] { OpenDataset(dir.path(), options); }), HasSubstr("first_frame"));
}

TEST(KittiDataset, OfficialLayoutPoses) {
  TempDir dir;
  KittiFixture fixture;
  fixture.poses = false;
  WriteKittiFolder(dir / "dataset/sequences/06", fixture);
  WriteText(dir / "dataset/poses/06.txt",
            "1 0 0 5 0 1 0 0 0 0 1 0\n1 0 0 6 0 1 0 0 0 0 1 0\n1 0 0 7 0 1 0 0 0 0 1 0\n"
            "1 0 0 8 0 1 0 0 0 0 1 0\n1 0 0 9 0 1 0 0 0 0 1 0\n");  // One more row than images.
  auto dataset = OpenDataset(dir / "dataset/sequences/06/");
  ASSERT_TRUE(dataset->ground_truth().has_value());
  ASSERT_EQ(dataset->ground_truth()->size(), 4u);
  EXPECT_NEAR(dataset->ground_truth()->poses[3].T_w_c.translation().x(), 8.0, 1e-12);
}

TEST(KittiDataset, ErrorsNameTheFileAndTheFix) {
  TempDir dir;
  EXPECT_THAT(ErrorOf([&] { OpenDataset(dir / "absent"); }), HasSubstr("missing dataset folder"));
  DatasetOptions kitti;
  kitti.format = DatasetFormat::kKitti;
  EXPECT_THAT(ErrorOf([&] { OpenDataset(dir / "absent", kitti); }), HasSubstr("missing folder"));

  const auto fresh = [&](const std::string& name, const KittiFixture& f = KittiFixture()) {
    WriteKittiFolder(dir / name, f);
    return dir / name;
  };
  {
    const std::string seq = fresh("no_calib");
    std::filesystem::remove(seq + "/calib.txt");
    EXPECT_THAT(ErrorOf([&] { OpenDataset(seq); }), HasSubstr("calib.txt"));
  }
  {
    const std::string seq = fresh("short_calib");
    WriteText(seq + "/calib.txt", "P0: 1 0 0 0 0 1 0 0 0 0 1 0\nP1: 1 0 0 -0.5 0 1 0 0 0 0 1\n");
    EXPECT_THAT(ErrorOf([&] { OpenDataset(seq); }),
                HasSubstr("calib.txt:2: 'P1:' has 11 numbers, expected 12"));
  }
  {
    // fx = 0 in P1: named as such (not as a consequence, "baseline inf must be >= 0").
    const std::string seq = fresh("p1_fx0");
    WriteText(seq + "/calib.txt",
              "P0: 1 0 0 0 0 1 0 0 0 0 1 0\nP1: 0 0 0 -0.5 0 1 0 0 0 0 1 0\n");
    EXPECT_THAT(ErrorOf([&] { OpenDataset(seq); }),
                HasSubstr("P1(0,0) = 0 is not a focal length"));
  }
  {
    // Zero baseline (P1 = P0): refused, not run as a stereo rig with infinite depths.
    const std::string seq = fresh("zero_baseline");
    WriteText(seq + "/calib.txt",
              "P0: 1 0 0 0 0 1 0 0 0 0 1 0\nP1: 1 0 0 0 0 1 0 0 0 0 1 0\n");
    EXPECT_THAT(ErrorOf([&] { OpenDataset(seq); }), HasSubstr("P1 gives baseline 0 m"));
  }
  {
    const std::string seq = fresh("no_p1");
    WriteText(seq + "/calib.txt", "P0: 1 0 0 0 0 1 0 0 0 0 1 0\n");
    EXPECT_THAT(ErrorOf([&] { OpenDataset(seq); }), HasSubstr("no 'P1:' row"));
    EXPECT_THAT(ErrorOf([&] { OpenDataset(seq); }), HasSubstr("(force_mono / --mode mono)"));
    DatasetOptions mono;
    mono.force_mono = true;
    EXPECT_NO_THROW(OpenDataset(seq, mono));
  }
  {
    const std::string seq = fresh("times_count");
    WriteText(seq + "/times.txt", "0\n0.1\n0.2\n");
    EXPECT_THAT(ErrorOf([&] { OpenDataset(seq); }), HasSubstr("has 3 times but"));
  }
  {
    const std::string seq = fresh("times_order");
    WriteText(seq + "/times.txt", "0\n0.2\n0.1\n0.3\n");
    EXPECT_THAT(ErrorOf([&] { OpenDataset(seq); }), HasSubstr("times.txt:3"));
  }
  {
    const std::string seq = fresh("missing_right");
    std::filesystem::remove(seq + "/image_1/" + KittiName(2));
    const std::string msg = ErrorOf([&] { OpenDataset(seq); });
    EXPECT_THAT(msg, HasSubstr("missing right image '" + seq + "/image_1/000002.png'"));
    EXPECT_THAT(msg, HasSubstr("(force_mono / --mode mono)"));
  }
  {
    const std::string seq = fresh("misnumbered");
    std::filesystem::rename(seq + "/image_0/" + KittiName(3), seq + "/image_0/000007.png");
    EXPECT_THAT(ErrorOf([&] { OpenDataset(seq); }), HasSubstr("missing left image"));
  }
  {
    const std::string seq = fresh("short_poses");
    WriteText(seq + "/poses.txt", "1 0 0 0 0 1 0 0 0 0 1 0\n");
    EXPECT_THAT(ErrorOf([&] { OpenDataset(seq); }), HasSubstr("has 1 poses for 4 images"));
  }
  {
    const std::string seq = fresh("short_odometry");
    WriteText(seq + "/odometry.txt", "0 0 0 0 0 0 0 1\n0.1 0 0 1 0 0 0 1\n");
    const std::string msg = ErrorOf([&] { OpenDataset(seq); });
    EXPECT_THAT(msg, HasSubstr(seq + "/odometry.txt: no pose at the time of image 000002.png"));
    EXPECT_THAT(msg, HasSubstr("one pose per image time"));
  }
  {
    const std::string seq = fresh("wrong_size");
    cv::imwrite(seq + "/image_1/" + KittiName(2), RandomImage(60, 48, 0));
    auto dataset = OpenDataset(seq);  // Sizes are checked when a frame is read.
    Frame frame;
    ASSERT_TRUE(dataset->Next(&frame));
    ASSERT_TRUE(dataset->Next(&frame));
    const std::string msg = ErrorOf([&] { dataset->Next(&frame); });
    EXPECT_THAT(msg, HasSubstr("image_1/000002.png' is 60x48, expected 64x48"));
    EXPECT_THAT(msg, HasSubstr("the first image"));
  }
  {
    const std::string seq = fresh("corrupt");
    WriteText(seq + "/image_0/" + KittiName(1), "this is not a png");
    auto dataset = OpenDataset(seq);
    Frame frame;
    ASSERT_TRUE(dataset->Next(&frame));
    EXPECT_THAT(ErrorOf([&] { dataset->Next(&frame); }),
                HasSubstr("cannot decode image '" + seq + "/image_0/000001.png'"));
  }
  {
    const std::string seq = fresh("corrupt_first");
    WriteText(seq + "/image_0/" + KittiName(0), "");
    EXPECT_THAT(ErrorOf([&] { OpenDataset(seq); }), HasSubstr("cannot decode image"));
  }
}

// The frames Next() yields and the frames it reports as bad (FrameError), in order.
std::vector<std::string> Play(Dataset* dataset) {
  std::vector<std::string> out;
  Frame frame;
  for (;;) {
    try {
      if (!dataset->Next(&frame)) return out;
      out.push_back(std::to_string(frame.id.value));
    } catch (const FrameError& e) {
      out.push_back("bad " + std::to_string(e.frame().value) + " at " +
                    std::to_string(e.t_ns()) + ": " + e.what());
    }
  }
}

// allow_missing_images: a missing or undecodable image of a frame after the first is a
// FrameError of that frame only, and the frames after it are read; without the option a
// missing image in the range to run is refused when opening; frames outside the range are not
// checked (times.txt may list more frames than the folder holds).
TEST(KittiDataset, BadImagesAfterTheFirstFrameAreFrameErrors) {
  TempDir dir;
  const std::string seq = dir / "seq";
  KittiFixture fixture;
  fixture.frames = 6;
  WriteKittiFolder(seq, fixture);
  std::filesystem::remove(seq + "/image_0/" + KittiName(2));
  WriteText(seq + "/image_1/" + KittiName(3), "this is not a png");
  std::filesystem::remove(seq + "/image_1/" + KittiName(5));
  DatasetOptions lenient;
  lenient.allow_missing_images = true;
  const std::vector<std::string> played = Play(OpenDataset(seq, lenient).get());
  ASSERT_EQ(played.size(), 6u);
  EXPECT_EQ(played[0], "0");
  EXPECT_EQ(played[1], "1");
  EXPECT_THAT(played[2], HasSubstr("bad 2 at 200000000: missing image '" + seq +
                                   "/image_0/000002.png'"));
  EXPECT_THAT(played[3], HasSubstr("bad 3 at 300000000: cannot decode image '" + seq +
                                   "/image_1/000003.png'"));
  EXPECT_EQ(played[4], "4");
  EXPECT_THAT(played[5], HasSubstr("bad 5"));

  EXPECT_THAT(ErrorOf([&] { OpenDataset(seq); }),
              HasSubstr("missing left image '" + seq + "/image_0/000002.png'"));
  DatasetOptions first_two;
  first_two.max_frames = 2;
  EXPECT_EQ(Play(OpenDataset(seq, first_two).get()), (std::vector<std::string>{"0", "1"}));
  DatasetOptions from_four;
  from_four.first_frame = 4;
  from_four.max_frames = 1;
  EXPECT_EQ(Play(OpenDataset(seq, from_four).get()), (std::vector<std::string>{"4"}));

  // The first frame of the run fixes the image size: never skipped.
  lenient.first_frame = 2;
  const std::string first = ErrorOf([&] { OpenDataset(seq, lenient); });
  EXPECT_THAT(first, HasSubstr("image_0/000002.png"));
  EXPECT_THAT(first, HasSubstr("--first_frame 3 starts after it"));

  // times.txt lists two frames more than the folder holds.
  WriteText(seq + "/times.txt", "0\n0.1\n0.2\n0.3\n0.4\n0.5\n0.6\n0.7\n");
  std::filesystem::remove(seq + "/poses.txt");
  EXPECT_THAT(ErrorOf([&] { OpenDataset(seq); }), HasSubstr("missing left image"));
  lenient.first_frame = 4;
  const std::vector<std::string> tail = Play(OpenDataset(seq, lenient).get());
  ASSERT_EQ(tail.size(), 4u);
  EXPECT_EQ(tail[0], "4");
  EXPECT_THAT(tail[3], HasSubstr("bad 7 at 700000000: missing image"));
}

TEST(KittiDataset, CalibrationOverride) {
  TempDir dir;
  KittiFixture fixture;
  fixture.stereo = false;
  WriteKittiFolder(dir / "seq", fixture);
  std::filesystem::remove(dir / "seq/calib.txt");  // Not needed with an override.
  DatasetOptions options;
  options.calibration_yaml = dir / "calib.yaml";

  WriteText(options.calibration_yaml,
            "%YAML:1.0\nfx: 80\nfy: 81\ncx: 32\ncy: 24\nwidth: 64\nheight: 48\n");
  auto plain = OpenDataset(dir / "seq", options);
  EXPECT_DOUBLE_EQ(plain->rig().left.fx, 80);
  EXPECT_DOUBLE_EQ(plain->rig().left.fy, 81);
  EXPECT_EQ(plain->rig().baseline, 0);

  // Distortion: the frames are undistorted and the rig has none.
  WriteText(options.calibration_yaml,
            "%YAML:1.0\nfx: 80\nfy: 80\ncx: 32\ncy: 24\nwidth: 64\n"
            "height: 48\nk1: -0.3\nk2: 0.1\n");
  auto undistorted = OpenDataset(dir / "seq", options);
  EXPECT_FALSE(undistorted->rig().left.HasDistortion());
  EXPECT_EQ(undistorted->rig().left.width, 64);
  Frame frame;
  ASSERT_TRUE(undistorted->Next(&frame));
  EXPECT_EQ(frame.left.size(), cv::Size(64, 48));
  EXPECT_GT(MaxAbsDiff(frame.left, RandomImage(64, 48, 0)), 0);  // Remapped.

  WriteText(options.calibration_yaml,
            "%YAML:1.0\nfx: 80\nfy: 80\ncx: 32\ncy: 24\nwidth: 640\nheight: 480\n");
  EXPECT_THAT(ErrorOf([&] { OpenDataset(dir / "seq", options); }),
              HasSubstr("is 64x48, expected 640x480 (from the calibration"));
  WriteText(options.calibration_yaml,
            "%YAML:1.0\nfx: 80\nfy: 80\ncx: 32\ncy: 24\nwidth: 64\nheight: 48\nbasline: 1\n");
  EXPECT_THAT(ErrorOf([&] { OpenDataset(dir / "seq", options); }),
              HasSubstr("unknown key 'basline'"));
  WriteText(options.calibration_yaml, "%YAML:1.0\nfx: 80\ncx: 32\ncy: 24\nwidth: 64\nheight: 48\n");
  EXPECT_THAT(ErrorOf([&] { OpenDataset(dir / "seq", options); }), HasSubstr("needs 'fy'"));

  // A stereo sequence needs a baseline in the override.
  WriteKittiFolder(dir / "stereo", KittiFixture());
  WriteText(options.calibration_yaml,
            "%YAML:1.0\nfx: 80\nfy: 80\ncx: 32\ncy: 24\nwidth: 64\nheight: 48\n");
  EXPECT_THAT(ErrorOf([&] { OpenDataset(dir / "stereo", options); }), HasSubstr("no 'baseline'"));
  WriteText(options.calibration_yaml,
            "%YAML:1.0\nfx: 80\nfy: 80\ncx: 32\ncy: 24\nwidth: 64\nheight: 48\nbaseline: 0.2\n");
  EXPECT_NEAR(OpenDataset(dir / "stereo", options)->rig().baseline, 0.2, 1e-15);
}

TEST(SyntheticDataset, DetectedByMarkerAndReadAsKitti) {
  TempDir dir;
  WriteKittiFolder(dir.path(), KittiFixture());
  WriteText(dir / "synth.yaml",
            "%YAML:1.0\nformat: \"dala-synthetic\"\nversion: 1\npreset: \"corridor\"\nseed: 3\n");
  EXPECT_EQ(DetectDatasetFormat(dir.path()), DatasetFormat::kSynthetic);
  auto dataset = OpenDataset(dir.path());
  EXPECT_EQ(dataset->format(), DatasetFormat::kSynthetic);
  EXPECT_EQ(dataset->size(), 4u);
  EXPECT_TRUE(dataset->is_stereo());
  EXPECT_TRUE(dataset->ground_truth().has_value());

  WriteText(dir / "synth.yaml", "%YAML:1.0\nformat: \"dala-synthetic\"\nversion: 2\n");
  EXPECT_THAT(ErrorOf([&] { OpenDataset(dir.path()); }), HasSubstr("version 2 is not supported"));
  WriteText(dir / "synth.yaml", "%YAML:1.0\nformat: \"other\"\nversion: 1\n");
  EXPECT_THAT(ErrorOf([&] { OpenDataset(dir.path()); }), HasSubstr("format is 'other'"));
}

TEST(KittiDataset, RealSequence06) {
  DALA_SKIP_WITHOUT_SHARED_DATA("kitti06_0000-0050");
  const std::string folder = testing::SharedDataDir() + "/kitti06_0000-0050";
  EXPECT_EQ(DetectDatasetFormat(folder), DatasetFormat::kKitti);
  auto dataset = OpenDataset(folder);
  EXPECT_EQ(dataset->size(), 51u);
  EXPECT_TRUE(dataset->is_stereo());
  const StereoRig& rig = dataset->rig();
  EXPECT_EQ(rig.left.width, 1226);
  EXPECT_EQ(rig.left.height, 370);
  EXPECT_DOUBLE_EQ(rig.left.fx, 707.0912);
  EXPECT_NEAR(rig.baseline, 0.537, 1e-3);
  ASSERT_TRUE(dataset->ground_truth().has_value());
  const Trajectory& gt = *dataset->ground_truth();
  ASSERT_EQ(gt.size(), 51u);
  EXPECT_POSE_NEAR(gt.poses[0].T_w_c, Pose::Identity(), 1e-6);
  // About 60 m of driving, mostly forward (+z of the first camera).
  EXPECT_GT(gt.PathLength(), 40.0);
  EXPECT_LT(gt.PathLength(), 80.0);
  EXPECT_GT(gt.poses.back().T_w_c.translation().z(), 40.0);
  Frame frame;
  ASSERT_TRUE(dataset->Next(&frame));
  EXPECT_EQ(frame.left.size(), cv::Size(1226, 370));
  EXPECT_EQ(frame.right.size(), cv::Size(1226, 370));
  EXPECT_EQ(frame.t_ns, 0);
  ASSERT_TRUE(dataset->Next(&frame));
  EXPECT_EQ(frame.t_ns, 100000000);
}

}  // namespace
}  // namespace dala
