// Frontend::ReturnLoopIds, the frontend's part of a loop the estimator did not close, on the
// rendered small loop with a stereo rig (the frontend alone: its dead reckoning places the
// queries). Two frontends see the same frames; at the first loop that relabels points one of them
// is told the loop was not closed. It then tracks those points under the ids they had before the
// loop, its database holds them so, and its next keyframe searches for a loop again; the other
// carries the old ids on and pauses its search.
#include <gtest/gtest.h>

#include <optional>
#include <set>

#include "core/sim/synthetic_sequence.h"
#include "frontend/frontend.h"
#include "tests/small_loop_drive.h"

namespace dala {
namespace {

int CountIds(const FrameMeasurement& m, const std::set<LandmarkId>& ids) {
  int n = 0;
  for (const FeatureObservation& o : m.observations) n += ids.count(o.landmark) > 0;
  return n;
}

TEST(ReturnLoopIds, TheNextFramesTrackThePointsUnderTheirIdsBeforeTheLoop) {
  const sim::SyntheticSequence seq(SmallLoopAt3Hz(160));
  Frontend returned(seq.rig(), FrontendOptions());
  Frontend kept(seq.rig(), FrontendOptions());
  std::optional<LoopDetection> loop;
  size_t i = 0;
  for (; i < seq.size() && !loop; ++i) {
    const Frame frame = seq.Render(i);
    const FrameMeasurement m = returned.Process(frame);
    kept.Process(frame);
    if (m.loop && !m.loop->relabelled.empty()) loop = m.loop;
  }
  ASSERT_TRUE(loop.has_value()) << "no loop relabelled points in " << seq.size() << " frames";
  const FrameId loop_frame(static_cast<int64_t>(i) - 1);
  std::set<LandmarkId> before, old;
  for (const auto& [id_before, old_id] : loop->relabelled) {
    before.insert(id_before);
    old.insert(old_id);
  }
  returned.ReturnLoopIds(*loop);

  // The loop keyframe's place-recognition entry (when it stored one) holds the ids before.
  for (const KeyframeEntry& e : returned.place_recognition().database().entries()) {
    if (e.frame != loop_frame) continue;
    int with_old = 0, with_before = 0;
    for (const LandmarkId id : e.landmark) {
      with_old += old.count(id) > 0;
      with_before += before.count(id) > 0;
    }
    EXPECT_EQ(with_old, 0);
    EXPECT_GT(with_before, 0);
  }

  // The frames after it, up to the next keyframe: the returned frontend tracks the points under
  // their ids before the loop, the other under the old ids. The keyframe is searched by the
  // returned frontend (it may find the place again and relabel: its measurement is read with the
  // ids before that loop), not by the other (its pause of keyframes_between_loops keyframes).
  bool keyframe_seen = false;
  for (size_t k = i; k < seq.size() && !keyframe_seen; ++k) {
    const Frame frame = seq.Render(k);
    const FrameMeasurement a = returned.Process(frame);
    const FrameMeasurement b = kept.Process(frame);
    const FrameMeasurement a_before = WithIdsBeforeLoop(a);
    std::cout << "[ measured ] frame " << k << (a.is_keyframe ? " (keyframe)" : "") << ": "
              << CountIds(a_before, before) << " of the loop's " << loop->relabelled.size()
              << " points under their ids before the loop (told), " << CountIds(b, old)
              << " under the old ids (not told)" << std::endl;
    EXPECT_EQ(CountIds(a_before, old), 0);
    EXPECT_GE(CountIds(a_before, before), static_cast<int>(loop->relabelled.size()) / 2);
    EXPECT_GE(CountIds(b, old), static_cast<int>(loop->relabelled.size()) / 2);
    if (a.is_keyframe) {
      keyframe_seen = true;
      EXPECT_GT(returned.place_recognition().last_stats().searched, 0);
      EXPECT_EQ(kept.place_recognition().last_stats().searched, 0);
    }
  }
  EXPECT_TRUE(keyframe_seen) << "no keyframe after the loop";
}

}  // namespace
}  // namespace dala
