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
  options.frames = std::getenv("DALA_VO_FRAMES") ? std::atoi(std::getenv("DALA_VO_FRAMES")) : 450;
  options.seed = 3;
  const sim::SyntheticSequence seq(options);
  const VoRun run = RunVisualOdometry(seq);
  EvalOptions eval;
  const EvalResult result = Evaluate(seq.ground_truth(), run.estimate, eval);
  ASSERT_TRUE(result.ok) << result.error;
  std::cout << "[ measured ] frames " << seq.size() << " path " << seq.PathLength()
            << " m, lost " << run.lost << ", keyframes " << run.keyframes << ", tracked/frame "
            << run.mean_tracked << "\n"
            << EvalResultToTable(result) << std::endl;
  EXPECT_EQ(run.lost, 0);
  ASSERT_TRUE(result.has_kitti);
  EXPECT_LT(result.kitti.t_err_percent, 2.0);
}

}  // namespace
}  // namespace dala
