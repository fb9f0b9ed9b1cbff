#ifndef DALA_TOOLS_REPORT_REPORT_DATA_H_
#define DALA_TOOLS_REPORT_REPORT_DATA_H_

// What report.html shows of a run, as the JSON its script reads (tools/report/page/report.js).
// Built from a run's results only (trajectory, map points, keyframe poses, report.json's frames
// and summary), never from an estimator's state: writing the report cannot change a run.
//
// Everything is shown in the ground truth's world when there is one, the estimate aligned onto
// it as `dala eval` and report.json align it (the EvalResult's alignment: SE(3), or Sim(3) for one
// camera); without ground truth, in the estimate's world. "Up" is the first pose's camera -y axis
// (the camera frame is y down): the map's height and the top view follow it.

#include <Eigen/Core>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "core/eval/evaluate.h"
#include "core/geometry.h"
#include "core/trajectory.h"

namespace dala::report {

// At most this many map points go into a report; a larger map is decimated (every k-th point, in
// the map's order, deterministic) and the page says how many it shows of how many. 200,000
// points keep report.html near 5 MB and the page fluid in a browser without a GPU.
constexpr size_t kMaxReportPoints = 200000;

struct ReportKeyframe {
  int64_t frame = -1;  // Frame index (-1: unknown, e.g. a map file's keyframe without stats).
  Pose T_w_c = Pose::Identity();  // In the estimate's world.
};

struct ReportInput {
  std::string title;      // What was run (the dataset path, or the map file).
  Trajectory trajectory;  // The estimate (empty for a map alone).
  // The ground truth and the evaluation of `trajectory` against it (Evaluate; its alignment
  // places everything in the ground truth's world). Both or neither.
  std::optional<Trajectory> ground_truth;
  std::optional<EvalResult> evaluation;
  std::vector<Eigen::Vector3d> points_w;  // Map points, in the estimate's world.
  std::vector<ReportKeyframe> keyframes;
  // report.json's "frames" (one object per frame: frame, t, status, keyframe, tracked, ...,
  // loop_old_frame, ms) and "summary"; null or empty for a map alone.
  nlohmann::json frames;
  nlohmann::json summary;
  std::string summary_text;         // The summary `dala run` printed.
  double image_aspect = 4.0 / 3.0;  // Width / height of the images (the keyframe frusta).
};

// The page's data: {"title", "up", "frame_of_reference", "points": {"xyz", "z", "shown",
// "total"}, "path": {"t", "frame", "xyz", "q"}, "ground_truth": {"xyz"}, "keyframes": {"frame",
// "xyz", "q"}, "loops": [{"frame", "old_frame", "closed", "a", "b"}], "lost": {"frame", "xyz"},
// "relocalised": {"frame", "xyz"}, "charts": {...per frame...}, "error": {"t", "frame", "m"},
// "scale": {"t", "percent"} (core/eval/scale_along_path.h: two points per segment),
// "summary", "summary_text", "aspect"}; positions rounded to the millimetre, orientations
// (quaternions x y z w) to 1e-4.
nlohmann::json ReportDataJson(const ReportInput& input);

// Keyframes of a run: the frames report.json marks keyframe that have a pose in the trajectory
// (matched by time).
std::vector<ReportKeyframe> KeyframesFromFrames(const nlohmann::json& frames,
                                                const Trajectory& trajectory);

}  // namespace dala::report

#endif  // DALA_TOOLS_REPORT_REPORT_DATA_H_
