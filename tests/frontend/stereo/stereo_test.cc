// Stereo matching against the renderer's exact depth: the triangulated depth of every matched
// left point is compared with the rendered z-depth at that pixel.
#include "frontend/stereo.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/sim/synthetic_sequence.h"
#include "frontend/frontend.h"

namespace dala {
namespace {

// The rendered rover loop (seed 4, default image noise of 1 grey level).
sim::SimOptions RoverOptions(int frames) {
  sim::SimOptions options;
  options.preset = "rover_loop";
  options.frames = frames;
  options.seed = 4;
  return options;
}

TEST(Stereo, DepthMatchesRenderedGroundTruth) {
  const sim::SyntheticSequence seq(RoverOptions(30));
  const StereoRig rig = seq.rig();
  int matched = 0, good = 0, wrong = 0;
  std::vector<double> rel_errors;
  for (size_t i : {0u, 15u, 29u}) {
    const Frame frame = seq.Render(i);
    cv::Mat depth;
    seq.RenderView(frame.T_w_c0_gt.value(), &depth);
    const HarrisOptions harris = SequenceHarrisOptions();
    const DetectedImage left = DetectHarris(frame.left, harris);
    const DetectedImage right = DetectHarris(frame.right, harris);
    const auto stereo = MatchStereo(rig, left, right, frame.left, frame.right, StereoOptions());
    for (size_t k = 0; k < stereo.size(); ++k) {
      if (!stereo[k]) continue;
      const Eigen::Vector2d& uv = left.points[k].uv;
      const float z_true = depth.at<float>(static_cast<int>(std::lround(uv.y())),
                                           static_cast<int>(std::lround(uv.x())));
      if (z_true <= 0.f) continue;  // Sky.
      ++matched;
      const double rel = std::abs(stereo[k]->p_c0.z() - z_true) / z_true;
      // A corner sits on a depth edge half the time: the nearest pixel may see the other side.
      if (rel > 0.2) {
        ++wrong;
        continue;
      }
      rel_errors.push_back(rel);
      // Within 3 sigma of the triangulation covariance (plus the pixel rounding of the truth).
      const double sigma_z = std::sqrt(stereo[k]->cov_p_c0(2, 2));
      good += std::abs(stereo[k]->p_c0.z() - z_true) < 3 * sigma_z + 0.01 * z_true;
    }
  }
  ASSERT_GT(matched, 600);
  std::sort(rel_errors.begin(), rel_errors.end());
  const double median = rel_errors[rel_errors.size() / 2];
  std::cout << "[ measured ] stereo points " << matched << ", gross " << wrong
            << ", median relative depth error " << median << ", within 3 sigma "
            << static_cast<double>(good) / rel_errors.size() << std::endl;
  EXPECT_LT(static_cast<double>(wrong) / matched, 0.05);
  EXPECT_LT(median, 0.01);
  EXPECT_GT(static_cast<double>(good) / rel_errors.size(), 0.9);
}

// Signed disparity bias against the rendered depth. A systematic disparity error delta biases
// every depth by delta / d relative, i.e. the metric scale of the trajectory (0.1 px at 10 px of
// disparity is 1 %): the median absolute error above cannot see it, the signed mean can.
// Only points on smooth depth (the 5x5 neighbourhood within 2 %) count, with the true
// disparity fx b / z from the bilinearly interpolated inverse depth at the sub-pixel point.
TEST(Stereo, DisparityHasNoSignedBias) {
  const sim::SyntheticSequence seq(RoverOptions(30));
  const StereoRig rig = seq.rig();
  const double fb = rig.left.fx * rig.baseline;
  StereoOptions stereo_options;
  stereo_options.max_depth_baselines = 1e3;  // Measure the far points too.
  // Sums of the signed error per band of true disparity: [0, 10), [10, 20), [20, inf) px.
  double sum[3] = {0, 0, 0};
  int count[3] = {0, 0, 0};
  for (size_t i : {0u, 5u, 10u, 15u, 20u, 29u}) {
    const Frame frame = seq.Render(i);
    cv::Mat depth;
    seq.RenderView(frame.T_w_c0_gt.value(), &depth);
    const HarrisOptions harris = SequenceHarrisOptions();
    const DetectedImage left = DetectHarris(frame.left, harris);
    const DetectedImage right = DetectHarris(frame.right, harris);
    const auto stereo = MatchStereo(rig, left, right, frame.left, frame.right, stereo_options);
    for (size_t k = 0; k < stereo.size(); ++k) {
      if (!stereo[k]) continue;
      const Eigen::Vector2d& uv = left.points[k].uv;
      const int x0 = static_cast<int>(std::floor(uv.x()));
      const int y0 = static_cast<int>(std::floor(uv.y()));
      if (x0 < 2 || y0 < 2 || x0 + 3 >= depth.cols || y0 + 3 >= depth.rows) continue;
      float z_min = std::numeric_limits<float>::max(), z_max = 0.f;
      for (int y = y0 - 2; y <= y0 + 3; ++y) {
        for (int x = x0 - 2; x <= x0 + 3; ++x) {
          z_min = std::min(z_min, depth.at<float>(y, x));
          z_max = std::max(z_max, depth.at<float>(y, x));
        }
      }
      if (z_min <= 0.f || z_max > 1.02f * z_min) continue;  // Sky or a depth edge.
      const double ax = uv.x() - x0, ay = uv.y() - y0;
      const double inverse_depth = (1 - ax) * (1 - ay) / depth.at<float>(y0, x0) +
                                   ax * (1 - ay) / depth.at<float>(y0, x0 + 1) +
                                   (1 - ax) * ay / depth.at<float>(y0 + 1, x0) +
                                   ax * ay / depth.at<float>(y0 + 1, x0 + 1);
      const double d_true = fb * inverse_depth;
      const double error = (uv.x() - stereo[k]->u_right) - d_true;
      if (std::abs(error) > 2.0) continue;  // Gross mismatch: counted by the test above.
      const int band = d_true < 10 ? 0 : (d_true < 20 ? 1 : 2);
      sum[band] += error;
      ++count[band];
    }
  }
  const int total = count[0] + count[1] + count[2];
  const double mean = (sum[0] + sum[1] + sum[2]) / total;
  std::cout << "[ measured ] signed disparity error, mean " << mean << " px over " << total
            << " points; by band [0,10) " << sum[0] / count[0] << " (" << count[0] << "), [10,20) "
            << sum[1] / count[1] << " (" << count[1] << "), [20,inf) " << sum[2] / count[2] << " ("
            << count[2] << ")" << std::endl;
  ASSERT_GT(total, 1000);
  // Measured 0.003 px overall and |0.012| at most per band; 0.03 px would be a 0.3 % scale
  // error at 10 px of disparity.
  EXPECT_LT(std::abs(mean), 0.03);
  for (int band = 0; band < 3; ++band) {
    ASSERT_GT(count[band], 60) << "band " << band;
    EXPECT_LT(std::abs(sum[band] / count[band]), 0.04) << "band " << band;
  }
}

// Far points are matched but returned without depth (the close/far limit of stereo.h).
TEST(Stereo, DepthIsKeptOnlyUpToTheBaselineLimit) {
  const sim::SyntheticSequence seq(RoverOptions(10));
  const StereoRig rig = seq.rig();
  const Frame frame = seq.Render(0);
  const HarrisOptions harris = SequenceHarrisOptions();
  const DetectedImage left = DetectHarris(frame.left, harris);
  const DetectedImage right = DetectHarris(frame.right, harris);
  StereoOptions far;
  far.max_depth_baselines = 1e3;
  StereoOptions near = far;
  near.max_depth_baselines = 20.0;
  near.min_points_with_depth = 0;
  const auto all = MatchStereo(rig, left, right, frame.left, frame.right, far);
  const auto kept = MatchStereo(rig, left, right, frame.left, frame.right, near);
  int n_all = 0, n_kept = 0, n_far = 0;
  for (size_t k = 0; k < all.size(); ++k) {
    n_all += all[k].has_value();
    if (all[k] && all[k]->p_c0.z() > 20.0 * rig.baseline) ++n_far;
    if (!kept[k]) continue;
    ++n_kept;
    EXPECT_LE(kept[k]->p_c0.z(), 20.0 * rig.baseline + 1e-9);
    // A kept point is the same measurement as without the limit.
    ASSERT_TRUE(all[k].has_value());
    EXPECT_EQ(kept[k]->u_right, all[k]->u_right);
  }
  EXPECT_GT(n_far, 50);
  EXPECT_EQ(n_kept, n_all - n_far);

  // Too few near points: the nearest far ones keep their depth up to min_points_with_depth.
  StereoOptions topped_up = near;
  topped_up.min_points_with_depth = n_kept + 20;
  const auto topped = MatchStereo(rig, left, right, frame.left, frame.right, topped_up);
  int n_topped = 0;
  double nearest_dropped = 0, farthest_added = 1e9;
  for (size_t k = 0; k < all.size(); ++k) {
    if (topped[k]) {
      ++n_topped;
      ASSERT_TRUE(all[k].has_value());
      EXPECT_EQ(topped[k]->u_right, all[k]->u_right);
      if (!kept[k]) farthest_added = std::min(farthest_added, 1.0 / topped[k]->p_c0.z());
    } else if (all[k]) {
      nearest_dropped = std::max(nearest_dropped, 1.0 / all[k]->p_c0.z());
    }
  }
  EXPECT_EQ(n_topped, n_kept + 20);
  EXPECT_GE(farthest_added, nearest_dropped);  // The added ones are the nearest of the far.

  StereoOptions invalid;
  invalid.max_depth_baselines = -1;
  EXPECT_FALSE(invalid.IsValid(nullptr));
  invalid = StereoOptions();
  invalid.min_points_with_depth = -1;
  EXPECT_FALSE(invalid.IsValid(nullptr));
}

}  // namespace
}  // namespace dala
