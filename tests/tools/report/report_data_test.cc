// report.html's data and page (tools/report): what the page is given of a run, decimation of
// large maps, loop edges, lost and relocalised frames, the frame of reference, and a page whose
// inline data cannot end its <script> element early.
#include "tools/report/report_data.h"

#include <gtest/gtest.h>

#include <string>

#include "tools/report/report_html.h"

namespace dala::report {
namespace {

Pose At(double x) {
  Pose T = Pose::Identity();
  T.translation() = Eigen::Vector3d(x, 0, 0);
  return T;
}

nlohmann::json Frame(int i, const std::string& status, bool keyframe = false) {
  return {{"frame", i},
          {"t", 0.1 * i},
          {"status", status},
          {"keyframe", keyframe},
          {"features", 100},
          {"tracked", 80},
          {"landmarks", 50},
          {"loop", false},
          {"loop_closed", false},
          {"loop_old_frame", nullptr},
          {"ms", {{"total", 12.5}}}};
}

ReportInput FiveFrames() {
  ReportInput input;
  input.title = "five";
  input.frames = nlohmann::json::array();
  for (int i = 0; i < 5; ++i) {
    // Frame 2 is lost (no pose); frame 3 is the first placed again.
    if (i != 2) input.trajectory.Add(static_cast<int64_t>(i) * 100000000, At(i));
    input.frames.push_back(Frame(i, i == 2 ? "lost" : "tracking", i == 0 || i == 4));
  }
  input.frames[4]["loop"] = true;
  input.frames[4]["loop_closed"] = true;
  input.frames[4]["loop_old_frame"] = 0;
  return input;
}

TEST(ReportData, MarksLostRelocalisedFramesLoopsAndKeyframes) {
  ReportInput input = FiveFrames();
  input.keyframes = KeyframesFromFrames(input.frames, input.trajectory);
  ASSERT_EQ(input.keyframes.size(), 2u);
  EXPECT_EQ(input.keyframes[1].frame, 4);
  const nlohmann::json data = ReportDataJson(input);
  EXPECT_EQ(data["path"]["xyz"].size(), 12u);  // 4 poses
  // The lost frame is marked where the run last had a pose (frame 1, x = 1).
  ASSERT_EQ(data["lost"]["frame"], nlohmann::json::array({2}));
  EXPECT_DOUBLE_EQ(data["lost"]["xyz"][0].get<double>(), 1.0);
  ASSERT_EQ(data["relocalised"]["frame"], nlohmann::json::array({3}));
  ASSERT_EQ(data["loops"].size(), 1u);
  EXPECT_EQ(data["loops"][0]["old_frame"], 0);
  EXPECT_TRUE(data["loops"][0]["closed"].get<bool>());
  EXPECT_DOUBLE_EQ(data["loops"][0]["a"][0].get<double>(), 4.0);
  EXPECT_DOUBLE_EQ(data["loops"][0]["b"][0].get<double>(), 0.0);
  EXPECT_EQ(data["charts"]["status"], nlohmann::json::array({1, 1, 2, 1, 1}));
  EXPECT_EQ(data["charts"]["keyframe"], nlohmann::json::array({1, 0, 0, 0, 1}));
  EXPECT_FALSE(data.contains("ground_truth"));
}

TEST(ReportData, ShowsEverythingInTheGroundTruthWorld) {
  ReportInput input = FiveFrames();
  // The ground truth is the estimate moved 10 m along y: the aligned estimate lies on it.
  Trajectory gt;
  for (const StampedPose& p : input.trajectory.poses) {
    Pose T = p.T_w_c;
    T.translation().y() += 10.0;
    gt.Add(p.t_ns, T);
  }
  input.points_w = {Eigen::Vector3d(0, 0, 5)};
  EvalOptions eval;
  eval.alignment = AlignmentType::kSE3;
  input.ground_truth = gt;
  input.evaluation = Evaluate(gt, input.trajectory, eval);
  ASSERT_TRUE(input.evaluation->ok) << input.evaluation->error;
  const nlohmann::json data = ReportDataJson(input);
  EXPECT_NEAR(data["path"]["xyz"][1].get<double>(), 10.0, 1e-3);
  EXPECT_NEAR(data["points"]["xyz"][1].get<double>(), 10.0, 1e-3);
  EXPECT_EQ(data["ground_truth"]["xyz"].size(), 12u);
  EXPECT_EQ(data["error"]["m"].size(), 4u);
}

TEST(ReportData, DecimatesALargeMap) {
  ReportInput input;
  const size_t n = 2 * kMaxReportPoints + 10;
  for (size_t i = 0; i < n; ++i) input.points_w.emplace_back(i * 1e-3, 0, 0);
  const nlohmann::json data = ReportDataJson(input);
  EXPECT_EQ(data["points"]["total"], n);
  const size_t shown = data["points"]["shown"];
  EXPECT_LE(shown, kMaxReportPoints);
  EXPECT_GT(shown, kMaxReportPoints / 2);
  EXPECT_EQ(data["points"]["xyz"].size(), 3 * shown);
}

TEST(ReportHtml, InlineDataCannotEndItsScript) {
  ReportInput input;
  input.title = "</script><script>alert(1)</script>";
  const std::string html = ReportHtml(ReportDataJson(input));
  EXPECT_EQ(html.find("</script><script>alert"), std::string::npos);
  EXPECT_NE(html.find("<\\/script><script>alert(1)<\\/script>"), std::string::npos);
  // three.js and the page's script are inline: no src to fetch.
  EXPECT_NE(html.find("THREE.OrbitControls"), std::string::npos);
  EXPECT_EQ(html.find("<script src"), std::string::npos);
  EXPECT_NE(html.find("&lt;/script&gt;"), std::string::npos);  // The <title>.
}

}  // namespace
}  // namespace dala::report
