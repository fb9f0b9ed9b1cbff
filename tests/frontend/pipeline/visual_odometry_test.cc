// End to end: the frontend alone (visual motion estimation chained as dead reckoning) over the
// rendered rover loop, evaluated with the project's metrics against the exact ground truth.
#include <gtest/gtest.h>

#include <cstdlib>

#include "core/eval/evaluate.h"
#include "core/sim/synthetic_sequence.h"
#include "frontend/frontend.h"
#include "tests/test_util.h"

namespace dala {
namespace {

struct VoRun {
  Trajectory estimate;
  int lost = 0;
  int keyframes = 0;
  double mean_tracked = 0;
};

VoRun RunVisualOdometry(const sim::SyntheticSequence& seq) {
  Frontend frontend(seq.rig(), FrontendOptions());
  VoRun run;
  for (size_t i = 0; i < seq.size(); ++i) {
    const Frame frame = seq.Render(i);
    const FrameMeasurement m = frontend.Process(frame);
    run.lost += m.status == TrackingStatus::kLost;
    run.keyframes += m.is_keyframe;
    int tracked = 0;
    for (const auto& o : m.observations) tracked += o.track_length > 1;
    run.mean_tracked += tracked;
    run.estimate.Add(frame.t_ns, frontend.dead_reckoning_T_w_c());
  }
  run.mean_tracked /= seq.size();
  return run;
}

TEST(VisualOdometry, RoverLoopDriftIsSmall) {
  sim::SimOptions options;
  options.preset = "rover_loop";
  options.frames = 450;
  options.seed = 3;
  const sim::SyntheticSequence seq(options);
  const VoRun run = RunVisualOdometry(seq);
  EvalOptions eval;
  const EvalResult result = Evaluate(seq.ground_truth(), run.estimate, eval);
  ASSERT_TRUE(result.ok) << result.error;
  std::cout << "[ measured ] frames " << seq.size() << " path " << seq.PathLength() << " m, lost "
            << run.lost << ", keyframes " << run.keyframes << ", tracked/frame " << run.mean_tracked
            << "\n"
            << EvalResultToTable(result) << std::endl;
  EXPECT_EQ(run.lost, 0);
  ASSERT_TRUE(result.has_kitti);
  testing::ExpectWithinBound("frontend alone (visual odometry), rover loop, KITTI t_err",
                             result.kitti.t_err_percent, 0.134, "%");
}

// The second thread (right detection, first temporal matching beside the stereo matching) must
// not change anything: every measurement equal, bit for bit, with and without it.
TEST(VisualOdometry, SecondThreadDoesNotChangeTheMeasurements) {
  sim::SimOptions options;
  options.preset = "rover_loop";
  options.frames = 12;
  options.seed = 5;
  const sim::SyntheticSequence seq(options);
  FrontendOptions threaded, single;
  threaded.parallel_detection = true;
  single.parallel_detection = false;
  Frontend a(seq.rig(), threaded), b(seq.rig(), single);
  for (size_t i = 0; i < seq.size(); ++i) {
    const Frame frame = seq.Render(i);
    const FrameMeasurement ma = a.Process(frame), mb = b.Process(frame);
    ASSERT_EQ(ma.status, mb.status) << "frame " << i;
    ASSERT_EQ(ma.is_keyframe, mb.is_keyframe) << "frame " << i;
    ASSERT_EQ(ma.motion.has_value(), mb.motion.has_value()) << "frame " << i;
    if (ma.motion) {
      EXPECT_EQ(ma.motion->T_prev_cur.matrix(), mb.motion->T_prev_cur.matrix()) << "frame " << i;
      EXPECT_EQ(ma.motion->inliers, mb.motion->inliers) << "frame " << i;
    }
    ASSERT_EQ(ma.observations.size(), mb.observations.size()) << "frame " << i;
    for (size_t k = 0; k < ma.observations.size(); ++k) {
      const FeatureObservation &oa = ma.observations[k], &ob = mb.observations[k];
      EXPECT_EQ(oa.landmark, ob.landmark);
      EXPECT_EQ(oa.uv, ob.uv);
      EXPECT_EQ(oa.u_right, ob.u_right);
      EXPECT_EQ(oa.track_length, ob.track_length);
    }
  }
}

}  // namespace
}  // namespace dala
