#ifndef DALA_BACKEND_BA_DISPARITY_OFFSET_CALIBRATION_H_
#define DALA_BACKEND_BA_DISPARITY_OFFSET_CALIBRATION_H_

// Online calibration of a stereo rig's disparity offset (StereoIntrinsics::disparity_offset_px):
// one value for the rig, decided from the free estimates of many window solves, so that the
// trajectory does not carry the noise of a per-window estimate.
//
// Why (docs/backend.md, "The rig's disparity offset"): a real rig's rectification leaves its
// disparities a few tenths of a pixel off (KITTI 06: ~0.3 px too small), which the far points
// turn into a scale error of delta / d; estimated freely in every window the offset removes it
// (KITTI 06: 0.182 -> 0.027 m) but moves the scale of an exact rig with its noise (rendered
// runs +20-60 %). The estimates an exact rig gives are not pure noise either: scene-dependent
// biases keep a running mean within +-0.08 px for many windows (rendered presets, after 8
// windows), against ~0.3 px on KITTI. Hence two tests before an offset is used:
//   - magnitude: |mean| >= min_offset_px (0.15 px, twice the largest exact-rig mean measured
//     and half KITTI's), below which an offset cannot be told from the scene's bias; and
//   - agreement: |mean| >= min_mean_over_sd * sd of the estimates (the windows overlap, so sd,
//     not the standard error of the mean, is the scale of disagreement);
// after at least min_estimates (8: one window's worth of keyframes) estimates. Until both hold
// the offset is 0 (an exact rig's value). Once they hold the offset follows the running mean.
// The calibration stops (converged()) once the running mean has moved by at most stable_px over
// its last min_estimates values, after converged_after_estimates estimates: the offset is a
// property of the rig, and the aside solves cost time (SlidingWindowBa::EstimateOffsetAside).
//
// Deterministic: a pure function of the sequence of estimates.

#include <deque>
#include <string>

namespace dala {

class DisparityOffsetCalibration {
 public:
  struct Options {
    int min_estimates = 8;
    double min_offset_px = 0.15;
    double min_mean_over_sd = 3.0;
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
  // Running mean of the estimates (0 before the first).
  double mean_px() const { return n_ > 0 ? sum_ / n_ : 0.0; }

 private:
  Options options_;
  int n_ = 0;
  double sum_ = 0.0;
  double sum_sq_ = 0.0;
  std::deque<double> recent_means_;  // the last min_estimates running means.
  double offset_px_ = 0.0;
  bool converged_ = false;
};

}  // namespace dala

#endif  // DALA_BACKEND_BA_DISPARITY_OFFSET_CALIBRATION_H_
