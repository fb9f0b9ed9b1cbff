#include "frontend/local_map_search.h"

#include <gtest/gtest.h>

#include <unordered_map>
#include <vector>

#include "frontend/harris.h"
#include "tests/frontend/test_images.h"

namespace dala {
namespace {

// A still camera at the origin looking at a textured plane 5 m away: every detection of the
// image is a landmark on that plane, so the image seen again is found entirely in the map.
struct Scene {
  PinholeCamera camera;
  DetectedImage detection;
  std::vector<LandmarkId> ids;
  LocalMap MapAfter(FrameId frame) const {
    LocalMap map;
    map.frame = frame;
    for (size_t i = 0; i < ids.size(); ++i) {
      map.points.emplace_back(ids[i], camera.Unproject(detection.points[i].uv) * 5.0);
    }
    return map;
  }
};

Scene MakeScene() {
  Scene s;
  s.camera.width = 640;
  s.camera.height = 480;
  s.camera.fx = s.camera.fy = 500.0;
  s.camera.cx = 320.0;
  s.camera.cy = 240.0;
  s.detection = DetectHarris(testing::MakeTexturedImage(640, 480, 11), HarrisOptions());
  for (size_t i = 0; i < s.detection.points.size(); ++i) s.ids.push_back(LandmarkId(1000 + i));
  return s;
}

// Frame 1 remembers every point under its landmark id; frames 2 and 3 see none of them; after
// frame 3 they enter the map, and frame 4 (the same image) searches it.
int FoundAfterAGap(const Scene& s, bool stereo) {
  LocalMapSearch search(s.camera, LocalMapSearchOptions(), MatcherOptions::ForTracking(), stereo);
  std::vector<int> length(s.ids.size(), 1);
  search.Remember(FrameId(1), s.detection, s.ids, length);
  const std::vector<LandmarkId> none(s.ids.size());
  for (int frame : {2, 3}) search.Remember(FrameId(frame), s.detection, none, length);
  search.SetLocalMap(s.MapAfter(FrameId(3)));
  std::vector<LandmarkId> found(s.ids.size());
  std::vector<int> track_length(s.ids.size(), 1);
  const int n = search.Search(FrameId(3), Pose::Identity(), /*metric=*/true, s.detection, &found,
                              &track_length);
  int right = 0;
  for (size_t i = 0; i < found.size(); ++i) right += found[i] == s.ids[i] ? 1 : 0;
  EXPECT_EQ(right, n) << "every point found must get its own landmark's id";
  return n;
}

TEST(LocalMapSearch, FindsTheMapsLandmarksByTheirLastAppearance) {
  const Scene s = MakeScene();
  ASSERT_GT(s.ids.size(), 200u);
  // One camera keeps the appearance of an unmapped point for forget_after_frames (30): the
  // landmark it becomes later is found.
  EXPECT_GT(FoundAfterAGap(s, /*stereo=*/false), static_cast<int>(0.9 * s.ids.size()));
}

TEST(LocalMapSearch, AStereoRigForgetsUnmappedAppearancesAfterOneFrame) {
  // A stereo landmark enters the map at a frame that observes it, so an appearance unmapped
  // for two frames is of no use: forgotten (the store stays one frame's points, not 30).
  const Scene s = MakeScene();
  EXPECT_EQ(FoundAfterAGap(s, /*stereo=*/true), 0);
  // What was mapped is kept, whatever its age.
  LocalMapSearch search(s.camera, LocalMapSearchOptions(), MatcherOptions::ForTracking(), true);
  std::vector<int> length(s.ids.size(), 1);
  search.Remember(FrameId(1), s.detection, s.ids, length);
  search.SetLocalMap(s.MapAfter(FrameId(1)));
  const std::vector<LandmarkId> none(s.ids.size());
  for (int frame : {2, 3, 4}) search.Remember(FrameId(frame), s.detection, none, length);
  search.SetLocalMap(s.MapAfter(FrameId(4)));
  std::vector<LandmarkId> found(s.ids.size());
  std::vector<int> track_length(s.ids.size(), 1);
  EXPECT_GT(search.Search(FrameId(4), Pose::Identity(), true, s.detection, &found, &track_length),
            static_cast<int>(0.9 * s.ids.size()));
}

// A loop relabelled frame 1's points with an old lap's ids (5000 + i), and the estimator did not
// close it: the points take back their ids (Frontend::ReturnLoopIds), and so does the appearance
// frame 1 gave them. The map of the current ids finds them; the old ids keep no appearance.
TEST(LocalMapSearch, ALoopsRelabellingReturnedMovesTheAppearance) {
  const Scene s = MakeScene();
  std::vector<LandmarkId> old_ids;
  std::unordered_map<LandmarkId, LandmarkId> back;
  for (size_t i = 0; i < s.ids.size(); ++i) {
    old_ids.push_back(LandmarkId(5000 + i));
    back[old_ids.back()] = s.ids[i];
  }
  Scene old_lap = s;
  old_lap.ids = old_ids;
  // `returned_at`: the frame whose appearances the rename moves (0: none); `mapped_then`: the
  // map of the old ids is frame 1's when the rename happens (the System hands it over first).
  const auto found_in = [&](const LocalMap& map, int returned_at, bool mapped_then = false) {
    LocalMapSearch search(s.camera, LocalMapSearchOptions(), MatcherOptions::ForTracking(), false);
    search.Remember(FrameId(1), s.detection, old_ids, std::vector<int>(s.ids.size(), 1));
    if (mapped_then) search.SetLocalMap(old_lap.MapAfter(FrameId(1)));
    if (returned_at > 0) search.RenameRemembered(FrameId(returned_at), back);
    search.SetLocalMap(map);
    std::vector<LandmarkId> found(s.ids.size());
    std::vector<int> track_length(s.ids.size(), 1);
    return search.Search(FrameId(1), Pose::Identity(), true, s.detection, &found, &track_length);
  };
  const int n = static_cast<int>(s.ids.size());
  const int most = static_cast<int>(0.9 * n);
  EXPECT_EQ(found_in(s.MapAfter(FrameId(1)), 0), 0);
  EXPECT_GT(found_in(s.MapAfter(FrameId(1)), 1), most);
  EXPECT_GT(found_in(old_lap.MapAfter(FrameId(1)), 0), most);
  EXPECT_EQ(found_in(old_lap.MapAfter(FrameId(1)), 1), 0);
  // Only the appearances of the frame named move.
  EXPECT_EQ(found_in(s.MapAfter(FrameId(1)), 2), 0);
  EXPECT_GT(found_in(old_lap.MapAfter(FrameId(1)), 2), most);
  // An old id the map holds keeps its appearance (the search still needs one), and the current
  // id gets it too.
  EXPECT_GT(found_in(old_lap.MapAfter(FrameId(1)), 1, /*mapped_then=*/true), most);
  EXPECT_GT(found_in(s.MapAfter(FrameId(1)), 1, /*mapped_then=*/true), most);
}

}  // namespace
}  // namespace dala
