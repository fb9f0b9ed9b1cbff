#ifndef DALA_CORE_EVAL_SCALE_ALONG_PATH_H_
#define DALA_CORE_EVAL_SCALE_ALONG_PATH_H_

// The scale along the path: how the estimate's size compares with the ground truth's, piece by
// piece. One alignment of the whole run (Evaluate) hides a scale that drifts, as a single camera
// does through turns: a run that starts 10 % too small and ends 10 % too large can align to a
// middling scale. Here the paired poses are cut into consecutive segments of equal ground-truth
// path length; each segment's estimated positions p_e are aligned onto its ground truth p_g by
// Sim(3) (ComputeAlignment: p_g = s_k R p_e + t), and its relative scale is
//   r_k = s / s_k,
// s the whole run's alignment scale (1 for SE(3)). r_k = 1.05: after the run's alignment, the
// estimate of segment k is 5 % larger than the truth. In stereo r_k is the scale error itself;
// with one camera (Sim(3)) it is the drift about the run's average unit.

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/eval/evaluate.h"

namespace dala {

struct ScaleSegment {
  size_t first_pair = 0, last_pair = 0;  // Indices into EvalResult::pairs (inclusive).
  double from_m = 0.0, to_m = 0.0;       // Ground-truth path length at its ends.
  double relative_scale = 1.0;           // r_k above.
};

struct ScaleAlongPath {
  double segment_m = 0.0;  // Ground-truth path length of each segment.
  std::vector<ScaleSegment> segments;
  double min = 1.0, max = 1.0;  // Of relative_scale over the segments (1 when there are none).
  std::string note;             // Why there are no segments, when there are none.
};

// Cuts the evaluated pairs of `result` (ok) into `num_segments` segments of equal ground-truth
// path length. A segment with fewer than 3 pairs or less than 1e-3 of the path is left out, as
// is one whose alignment has no unique answer.
ScaleAlongPath MeasureScaleAlongPath(const EvalResult& result, int num_segments = 10);

// {"segment_m", "min", "max", "segments": [{"from_m", "to_m", "scale"}], "note"?}.
nlohmann::json ScaleAlongPathToJson(const ScaleAlongPath& scale);

}  // namespace dala

#endif  // DALA_CORE_EVAL_SCALE_ALONG_PATH_H_
