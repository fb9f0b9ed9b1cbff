#ifndef DALA_BACKEND_SYSTEM_ENSEMBLE_H_
#define DALA_BACKEND_SYSTEM_ENSEMBLE_H_

// dala::SystemEnsemble: several pipelines over the same frames that differ only in their RANSAC
// draws, stepped together, and the mean of their trajectories (`dala run --draws N`).
//
// Why: a run's error is part bias, part chance. Two runs whose RANSACs draw other samples (the
// frame-to-frame motion, the first pair of one camera, the matcher) keep other inliers, other
// tracks and other landmarks, and one camera's scale drifts another way: on KITTI 06 the draws of
// one start spread its ATE by a factor of 1.25 (standard deviation of log ATE 0.23). The runs
// share what the data and the method get wrong and not what chance does, so their mean
// (core/eval/trajectory_fusion.h) keeps the first and averages the second (docs/evaluation.md,
// "Several draws in one run"; the measured gains in docs/results.md).
//
//   dala::SystemEnsembleOptions draws;
//   draws.draws = 3;
//   draws.threads = 2;
//   dala::SystemEnsemble runs(dataset->rig(), dala::SystemOptions(), draws);
//   dala::Frame frame;
//   while (dataset->Next(&frame)) runs.Track(frame);
//   runs.Finish();
//   const std::vector<dala::Trajectory> trajectories = runs.Trajectories();
//   dala::FusedTrajectory fused;
//   std::string why;
//   if (!runs.Fuse(trajectories, runs.FusableDraws(trajectories), &fused, &why)) ...;
//
// Draw k is a System whose options are the given ones with ransac_order_seed + k and
// frontend.motion.seed + k (every RANSAC of the run draws otherwise): draw 0 is the run the
// options alone give, and its world (the first frame's camera) and unit are the fused
// trajectory's (when it has a trajectory). Each System is deterministic, so the results do not
// depend on the threads; draw k always runs on thread k % threads (the calling thread is thread
// 0), so that a System's own worker threads are always started from one thread and its
// thread-local scratch stays warm. Memory and work grow with the draws, the wall time per frame
// by the draws over the threads (the frame's detection is shared). Track and Finish may throw
// what System::Track and Finish throw: the errors that change nothing (a frame out of time
// order, an image that does not suit the rig) leave every draw as it was; after any other
// exception the draws may be out of step, and the ensemble should be discarded.

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "backend/system.h"
#include "core/eval/trajectory_fusion.h"
#include "frontend/worker_thread.h"

namespace dala {

struct SystemEnsembleOptions {
  int draws = 1;    // Pipelines; draw k has ransac_order_seed + k.
  int threads = 1;  // Threads that step them (the calling thread and threads - 1 workers).

  bool IsValid(std::string* why) const;
};

class SystemEnsemble {
 public:
  // Throws dala::Error for invalid options (as System does, and for SystemEnsembleOptions).
  SystemEnsemble(const StereoRig& rig, const SystemOptions& options,
                 const SystemEnsembleOptions& ensemble);

  // Tracks the frame in every draw and returns the first draw's result. The images are detected
  // (and matched in stereo) once for all draws (ComputeFrameFeatures: they do not depend on the
  // draw). An exception thrown by a draw's System::Track is rethrown here (the first draw's
  // first) once every draw returned; a frame that does not suit the rig throws before any draw
  // sees it.
  TrackResult Track(const Frame& frame);
  void SkipFrame(FrameId frame, int64_t t_ns, const std::string& note);
  // Every draw starts in the saved map (System::UseMap).
  void UseMap(const SavedMap& map);
  // The global refinement of every draw (System::Finish), one summary per draw.
  std::vector<RefinementSummary> Finish(const std::function<bool()>& stop_requested = nullptr);

  int size() const { return static_cast<int>(draws_.size()); }
  const System& draw(int k) const { return *draws_.at(k); }
  const System& first() const { return *draws_.front(); }
  uint64_t seed(int k) const { return draws_.at(k)->options().ransac_order_seed; }
  // Every draw's trajectory as it is now (System::trajectory).
  std::vector<Trajectory> Trajectories() const;
  // The wall time of each Track call, every draw included [ms].
  const std::vector<double>& wall_ms() const { return wall_ms_; }

  // How the draws are brought onto one another: SE(3) when the first draw's unit is metric,
  // Sim(3) when it is arbitrary (one camera).
  AlignmentType FusionAlignment() const;
  // The draws whose trajectory (one per draw, e.g. Trajectories()) can take part in a fusion:
  // those with at least 3 poses (an alignment needs 3), in draw order. A draw of one camera that
  // never initialised has none.
  std::vector<int> FusableDraws(const std::vector<Trajectory>& trajectories) const;
  // The trajectories of `draws` (non-empty, e.g. FusableDraws()) fused into the world and unit
  // of the first of them (FuseTrajectories). Returns false and says why, naming the draws by
  // their seeds, when they cannot be fused (fewer than 3 frames shared).
  bool Fuse(const std::vector<Trajectory>& trajectories, const std::vector<int>& draws,
            FusedTrajectory* fused, std::string* why) const;

 private:
  // Runs task(k) for every draw k, draw k on thread k % threads; rethrows the first exception.
  template <typename Task>
  void ForEachDraw(const Task& task);

  std::vector<std::unique_ptr<System>> draws_;
  std::vector<WorkerThread> workers_;  // threads - 1 of them: thread t > 0 is workers_[t - 1].
  std::vector<double> wall_ms_;
};

}  // namespace dala

#endif  // DALA_BACKEND_SYSTEM_ENSEMBLE_H_
