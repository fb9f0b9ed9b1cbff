// The library API called wrongly, in-process: each mistake of the caller is a dala::Error that
// names it, the host process goes on, and the System is as it was (the next good frame is
// tracked as if the bad one had never come). DESIGN.md, "Error handling".
#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>
#include <string>

#include "backend/system.h"
#include "core/error.h"
#include "core/sim/synthetic_sequence.h"
#include "tests/test_util.h"

namespace dala {
namespace {

sim::SimOptions SmallRover() {
  sim::SimOptions sim;
  sim.preset = "rover_loop";
  sim.frames = 6;
  sim.seed = 3;
  return sim;
}

// Calls Track(bad) and returns the error's message ("" when nothing was thrown).
std::string TrackError(System* system, const Frame& bad) {
  return testing::ErrorOf([&] { system->Track(bad); });
}

TEST(SystemMisuse, AWrongFrameIsAnErrorThatChangesNothing) {
  const sim::SyntheticSequence seq(SmallRover());
  System clean(seq.rig(), SystemOptions());
  System misused(seq.rig(), SystemOptions());
  for (size_t i = 0; i < seq.size(); ++i) {
    const Frame frame = seq.Render(i);
    if (i == 3) {
      Frame small = frame;
      cv::resize(frame.left, small.left, cv::Size(), 0.5, 0.5);
      std::string error = TrackError(&misused, small);
      EXPECT_NE(error.find("left image is 376x240 pixels"), std::string::npos) << error;
      EXPECT_NE(error.find("752x480"), std::string::npos) << error;

      Frame colour = frame;
      cv::cvtColor(frame.left, colour.left, cv::COLOR_GRAY2BGR);
      error = TrackError(&misused, colour);
      EXPECT_NE(error.find("CV_8UC3"), std::string::npos) << error;
      EXPECT_NE(error.find("cv::cvtColor"), std::string::npos) << error;

      Frame no_right_size = frame;
      no_right_size.right = cv::Mat(10, 10, CV_8UC1, cv::Scalar(0));
      error = TrackError(&misused, no_right_size);
      EXPECT_NE(error.find("right image is 10x10"), std::string::npos) << error;

      Frame empty = frame;
      empty.left = cv::Mat();
      error = TrackError(&misused, empty);
      EXPECT_NE(error.find("left image is empty"), std::string::npos) << error;

      Frame earlier = frame;
      earlier.t_ns = misused.stats().back().t_ns - 1;
      error = TrackError(&misused, earlier);
      EXPECT_NE(error.find("time order"), std::string::npos) << error;
    }
    const TrackResult a = clean.Track(frame);
    const TrackResult b = misused.Track(frame);
    EXPECT_EQ(a.status, b.status) << "frame " << i;
    EXPECT_TRUE(a.T_w_c.isApprox(b.T_w_c, 0.0)) << "frame " << i;
  }
  EXPECT_EQ(clean.stats().size(), misused.stats().size());
}

TEST(SystemMisuse, InvalidOptionsAreAnError) {
  const sim::SyntheticSequence seq(SmallRover());
  SystemOptions options;
  options.ba.final_ba = "sometimes";
  try {
    System system(seq.rig(), options);
    FAIL() << "no error for ba.final_ba=sometimes";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("final_ba"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace dala
