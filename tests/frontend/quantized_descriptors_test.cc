// The 8-bit descriptors of the place-recognition database and the map file
// (core/quantized_descriptors.h) on real patch descriptors: what they change in ZNCCs and in
// what the matcher finds.
#include "core/quantized_descriptors.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "frontend/harris.h"
#include "frontend/matcher.h"
#include "tests/frontend/test_images.h"

namespace dala {
namespace {

using testing::MakeTexturedImage;
using testing::SimilarityAboutCentre;
using testing::Warp;

DetectedImage Quantized(const DetectedImage& d) {
  QuantizedDescriptors q(d.descriptors.cols);
  for (int r = 0; r < d.descriptors.rows; ++r) q.AppendRow(d.descriptors, r);
  DetectedImage out = d;
  out.descriptors = q.Expand();
  out.neighbour_cache = std::make_shared<NeighbourCache>();
  return out;
}

TEST(QuantizedDescriptorsTest, ExpandedRowsAreUnitZeroMeanAndKeepTheirZncc) {
  const DetectedImage d = DetectHarris(MakeTexturedImage(640, 480, 11), HarrisOptions());
  ASSERT_GT(d.descriptors.rows, 500);
  const DetectedImage q = Quantized(d);
  EXPECT_EQ(q.descriptors.rows, d.descriptors.rows);
  for (int r = 0; r < q.descriptors.rows; ++r) {
    const cv::Mat row = q.descriptors.row(r);
    EXPECT_NEAR(cv::norm(row), 1.0, 1e-5);
    EXPECT_NEAR(cv::sum(row)[0], 0.0, 1e-4);
  }
  // ZNCC of every pair among the first 300 rows, before and after (bound: twice the largest
  // change seen at writing, 2.4e-3; an error in the rounding or the scale gives > 1e-2).
  double max_change = 0.0;
  const int n = 300;
  for (int a = 0; a < n; ++a) {
    for (int b = a + 1; b < n; ++b) {
      const double before = d.descriptors.row(a).dot(d.descriptors.row(b));
      const double after = q.descriptors.row(a).dot(q.descriptors.row(b));
      max_change = std::max(max_change, std::abs(after - before));
    }
  }
  EXPECT_LT(max_change, 5e-3);
  EXPECT_GT(max_change, 0.0);  // It is a quantisation, not a copy.
}

TEST(QuantizedDescriptorsTest, QuantizedRowsAreCompactAndExpandAsTheFreeFunctions) {
  const float row[5] = {0.5f, -0.25f, 0.f, 0.125f, -0.375f};
  QuantizedDescriptors q(5);
  q.Append(row);
  int8_t samples[5];
  QuantizeDescriptor(row, 5, samples);
  EXPECT_EQ(samples[0], 127);
  EXPECT_EQ(samples[1], -64);  // -0.25 * 254 rounded away from zero.
  q.AppendQuantized(samples);
  EXPECT_EQ(q.rows(), 2);
  EXPECT_GE(q.bytes(), 10u);
  EXPECT_LT(q.bytes(), 10u * sizeof(float));
  float a[5], b[5];
  q.ExpandRow(0, a);
  q.ExpandRow(1, b);
  for (int k = 0; k < 5; ++k) EXPECT_EQ(a[k], b[k]);
  // A flat patch (all samples equal) has no direction: it expands to zeros, matching nothing.
  const float flat[5] = {0.2f, 0.2f, 0.2f, 0.2f, 0.2f};
  QuantizedDescriptors f(5);
  f.Append(flat);
  f.ExpandRow(0, a);
  for (int k = 0; k < 5; ++k) EXPECT_EQ(a[k], 0.f);
}

// What place recognition does with them: the old keyframe's descriptors quantised, the current
// image's not. The matcher must find (nearly) the same correct matches under rotation and scale.
TEST(QuantizedDescriptorsTest, MatcherFindsTheSameCorrespondences) {
  const cv::Mat image = MakeTexturedImage(640, 480, 7);
  const DetectedImage a = DetectHarris(image, HarrisOptions());
  const DetectedImage qa = Quantized(a);
  for (const auto& [angle, scale] : {std::pair<double, double>{0.0, 1.0}, {0.8, 1.0},
                                     {0.0, 1.5}, {2.3, 1.6}}) {
    const cv::Mat H = SimilarityAboutCentre(image.size(), angle, scale);
    const DetectedImage b = DetectHarris(Warp(image, H), HarrisOptions());
    const auto correct = [&](const DetectedImage& from) {
      int n = 0;
      for (const Match& m : MatchPoints(from, b, MatcherOptions())) {
        if ((testing::ApplyH(H, from.points[m.i].uv) - b.points[m.j].uv).norm() < 3.0) ++n;
      }
      return n;
    };
    const int full = correct(a);
    const int quantized = correct(qa);
    ASSERT_GT(full, 200) << angle << " " << scale;
    EXPECT_GE(quantized, 0.99 * full)  // The same counts at writing (2009, 1422, 708, 606).
        << "rotation " << angle << ", scale " << scale;
  }
}

}  // namespace
}  // namespace dala
