#ifndef DALA_BACKEND_BA_GLOBAL_BA_H_
#define DALA_BACKEND_BA_GLOBAL_BA_H_

// Global bundle adjustment: every keyframe of a run, every landmark two of them observe and
// every observation of it, in one Ceres problem (the offline refinement of a finished run, as
// COLMAP's final BA or ORB-SLAM's global BA after a loop). The sliding window solved each
// keyframe against the last few only, and a keyframe that left it kept the pose it had then:
// the scale of a monocular map, or the drift of a stereo one, was decided by a few keyframes at a
// time. Here each landmark ties together every keyframe that saw it, however far apart in time.
//
// Problem: min over the non-held poses T_w_c (SE(3) pose blocks, backend/ba/pose_block.h) and
// the points p_w of sum rho(|r|^2) over the reprojection residuals r (stereo or mono,
// backend/ba/reprojection_factors.h, whitened by each observation's sigma), rho Huber. Gauge:
// the `held` keyframes are constants (the estimator's window gauge: the first keyframe of a
// stereo map, the first two of a monocular one, whose distance fixes the unit). Tracks the run
// never mapped are triangulated first (Options::triangulate_unmapped). After a solve,
// observations failing the chi-square 95 % test (or with the point closer than min_depth) are
// removed and the problem solved again, at most max_outlier_rounds times. A landmark left with
// fewer than two observations leaves the problem (its position is not changed).
//
// Deterministic (ordered containers, one thread by default). Cost: SPARSE_SCHUR with SuiteSparse,
// the landmarks eliminated; it grows with the observations: KITTI 06 0-50 in stereo (51
// keyframes, 19,500 observations) about 3 s, a rendered 600-frame street drive (569 keyframes,
// 423,000 observations) 90 s, one thread on a 2-core machine (docs/backend.md, "Global BA after
// the run"). A caller's stop request, polled at every iteration, ends it with the poses and
// landmarks unchanged.

#include <Eigen/Core>
#include <functional>
#include <map>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "backend/ba/ba_loss.h"
#include "backend/ba/ba_types.h"
#include "core/geometry.h"
#include "core/types.h"

namespace dala {

struct GlobalBaOptions {
  RobustLoss loss = RobustLoss::kHuber;
  double loss_scale = 2.45;  // On the whitened residual norm, as the window's.
  int max_num_iterations = 50;
  double function_tolerance = 1e-7;
  int max_outlier_rounds = 2;  // Re-solves after removing outliers.
  double min_depth = 0.05;     // An observation of a point closer (or behind) is an outlier.
  int num_threads = 1;         // > 1 may change the result in the last bits.
  // Landmarks observed without a position (tracks the run never mapped) are triangulated
  // first: from their first stereo observation with at least min_disparity_px, else by DLT
  // over every view when the rays meet at min_parallax_deg (TriangulateViews). They join the
  // problem like the others (the outlier test then judges them); false: they are skipped.
  bool triangulate_unmapped = true;
  double min_disparity_px = 1.0;
  double min_parallax_deg = 1.0;
  // Stereo: the rig's disparity offset (StereoIntrinsics::disparity_offset_px) is one more
  // parameter, shared by every stereo residual, starting from K's value, with the prior
  // N(0, disparity_offset_prior_sigma_px^2) (the window's, SlidingWindowBa::Options). Every
  // keyframe is then solved under the offset that the whole run's views agree on, including
  // the keyframes that left the window before the online calibration knew it.
  bool estimate_disparity_offset = false;
  double disparity_offset_prior_sigma_px = 1.0;

  bool IsValid(std::string* why) const;
};

struct GlobalBaProblem {
  std::map<KeyframeId, Pose> keyframes;  // T_w_c, in: initial values, out: refined.
  std::set<KeyframeId> held;             // Constants (the gauge); ids not in keyframes: ignored.
  // Distances held between two keyframes' camera centres: the unit of a monocular map (its
  // first keyframe held, the second free but for its distance from the first: the 7-dof gauge,
  // where holding both poses would also freeze their relative rotation and direction as the
  // two-view initialisation estimated them). Residual (|c_b - c_a| - d) / (1e-6 d).
  struct FixedDistance {
    KeyframeId a, b;
    double distance = 0.0;
  };
  std::vector<FixedDistance> fixed_distances;
  // p_w, in/out. Out: also the landmarks triangulated here that stayed in the solution.
  std::map<LandmarkId, Eigen::Vector3d> landmarks;
  // Every observation (keyframe, observation); those of unknown keyframes or landmarks without
  // a position are skipped. Out: the outliers removed.
  std::vector<std::pair<KeyframeId, BaObservation>> observations;
};

struct GlobalBaSummary {
  int num_keyframes = 0;  // With at least one residual (held ones included).
  int num_landmarks = 0;
  int num_triangulated = 0;  // Of them, triangulated here (Options::triangulate_unmapped).
  int num_observations = 0;  // Residual blocks of the first solve.
  int num_outliers_removed = 0;
  int num_solves = 0;
  int num_iterations = 0;
  double initial_cost = 0.0;  // Ceres cost 0.5 sum rho(|r|^2): first solve's start...
  double final_cost = 0.0;    // ...and last solve's end.
  // The disparity offset of the solution (pixels): estimated (Options::estimate_disparity_offset
  // and a stereo residual) or K's.
  double disparity_offset_px = 0.0;
  double time_s = 0.0;
  bool usable = false;  // The last solve's IsSolutionUsable (false: nothing was changed).
  bool stopped = false;  // The caller's stop request ended it (usable is then false).

  // One line without the time (report.json keeps it apart: the rest is deterministic).
  std::string BriefReport() const;
};

// Refines problem->keyframes and problem->landmarks in place (see the file comment). With no
// residual (fewer than two keyframes sharing a landmark), nothing changes and usable is true.
// stop_requested (may be empty) is polled before each solve and at every solver iteration, from
// the calling thread: once it returns true the refinement ends with the poses and landmarks
// unchanged (stopped, not usable; observations already found to be outliers stay removed, as
// after a solve that fails).
GlobalBaSummary SolveGlobalBa(const StereoIntrinsics& K, const GlobalBaOptions& options,
                              GlobalBaProblem* problem,
                              const std::function<bool()>& stop_requested = nullptr);

}  // namespace dala

#endif  // DALA_BACKEND_BA_GLOBAL_BA_H_
