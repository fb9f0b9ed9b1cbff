// Stereo matching against the renderer's exact depth: the triangulated depth of every matched
// left point is compared with the rendered z-depth at that pixel.
#include "frontend/stereo.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "core/sim/synthetic_sequence.h"
#include "frontend/frontend.h"

namespace dala {
namespace {

TEST(Stereo, DepthMatchesRenderedGroundTruth) {
  sim::SimOptions options;
  options.preset = "rover_loop";
  options.frames = 30;
  options.seed = 4;
  options.noise_sigma = 1.0;
  const sim::SyntheticSequence seq(options);
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

}  // namespace
}  // namespace dala
