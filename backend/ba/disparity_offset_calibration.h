#ifndef DALA_BACKEND_BA_DISPARITY_OFFSET_CALIBRATION_H_
#define DALA_BACKEND_BA_DISPARITY_OFFSET_CALIBRATION_H_

// Online calibration of a stereo rig's disparity offset (StereoIntrinsics::disparity_offset_px):
// one value for the rig, decided from the free estimates of many window solves, so that the
// trajectory does not carry the noise of a per-window estimate.
//
// Why (docs/backend.md, "The rig's disparity offset"): a real rig's rectification leaves its
// disparities a few tenths of a pixel off (KITTI 06: ~0.25 px too small), which the far points
// turn into a scale error of delta / d. The per-window estimates of a real rig scatter with the
// scene (KITTI 06: 0.07-0.37 px within one 60 m drive); those of an exact rig centre on zero
// (rendered presets: |median| <= 0.055 px after 8 windows, <= 0.045 px at the end of a run).
//
// The statistic is the median m of the estimates (a few wild windows do not move it), and the
// offset used is a weight on it, not a gate, so that no setting flips the result:
//   offset = m * clamp((|m| - bias_px) / bias_px, 0, 1)
// zero while |m| is within what an exact rig shows (bias_px), all of m from 2 bias_px on, a
// ramp between; nothing before min_estimates estimates (the first windows are short and
// scatter most). The offset found online is not the last word: a run that ends with a non-zero
// offset is re-solved with every keyframe and the offset free (SlidingWindowEstimatorOptions::
// final_ba "rig_offset"), which is what decides the trajectory offline; the weight decides
// whether a rig has an offset at all, and what the online trajectory uses meanwhile.
// The calibration stops (converged()) once the median has moved by at most stable_px over its
// last min_estimates values, after converged_after_estimates estimates: the offset is a property
// of the rig, and the aside solves cost time (SlidingWindowBa::EstimateOffsetAside).
//
// Deterministic: a pure function of the sequence of estimates.

#include <deque>
#include <string>
#include <vector>

namespace dala {

class DisparityOffsetCalibration {
 public:
  struct Options {
    int min_estimates = 8;
    double bias_px = 0.075;
    int converged_after_estimates = 32;
    double stable_px = 0.01;
    // An estimate is taken only from a window whose keyframes span at least this many stereo
    // baselines: with less motion the left-image views cannot check the stereo depth, and the
    // offset is decided by weak couplings (pure rotation: -0.13 px over 8 windows).
    double min_window_span_baselines = 1.0;
    // SlidingWindowBa drops its marginalisation prior when the offset in use moves by more than
    // this from the one the prior was built with (the prior holds the old offset's scale).
    double max_prior_offset_change_px = 0.05;

    bool IsValid(std::string* why) const;
  };

  DisparityOffsetCalibration() = default;
  explicit DisparityOffsetCalibration(const Options& options) : options_(options) {}

  // One window's free estimate (pixels).
  void Add(double estimate_px);
  // The rig's offset to use now (0 until the tests above hold).
  double offset_px() const { return offset_px_; }
  // The calibration is done: further estimates are not needed.
  bool converged() const { return converged_; }
  int num_estimates() const { return n_; }
  // Median of the estimates (0 before the first).
  double median_px() const { return median_px_; }
  // The weight on the median in use (0..1, see the file comment).
  double weight() const { return median_px_ != 0.0 ? offset_px_ / median_px_ : 0.0; }

 private:
  Options options_;
  int n_ = 0;
  std::vector<double> estimates_;
  double median_px_ = 0.0;
  std::deque<double> recent_medians_;  // the last min_estimates medians.
  double offset_px_ = 0.0;
  bool converged_ = false;
};

}  // namespace dala

#endif  // DALA_BACKEND_BA_DISPARITY_OFFSET_CALIBRATION_H_
