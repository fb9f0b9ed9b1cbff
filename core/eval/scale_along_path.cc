#include "core/eval/scale_along_path.h"

#include <algorithm>

#include "core/eval/alignment.h"

namespace dala {

ScaleAlongPath MeasureScaleAlongPath(const EvalResult& result, int num_segments) {
  ScaleAlongPath out;
  const std::vector<double>& distance = result.pair_distance_m;
  if (!result.ok || num_segments < 1 || distance.size() != result.pairs.size() ||
      distance.size() < 3) {
    out.note = "too few evaluated poses";
    return out;
  }
  const double length = distance.back();
  out.segment_m = length / num_segments;
  if (!(length > 0.0)) {
    out.note = "the ground truth does not move";
    return out;
  }
  size_t begin = 0;
  for (int k = 0; k < num_segments; ++k) {
    const double to = k + 1 == num_segments ? length : out.segment_m * (k + 1);
    size_t end = begin;  // One past the segment's last pair.
    while (end < distance.size() && (distance[end] <= to || k + 1 == num_segments)) ++end;
    if (end - begin >= 3 && distance[end - 1] - distance[begin] > 1e-3 * length) {
      std::vector<Eigen::Vector3d> p_e, p_g;
      for (size_t i = begin; i < end; ++i) {
        p_e.push_back(result.pairs.T_w_c_est[i].translation());
        p_g.push_back(result.pairs.T_w_c_gt[i].translation());
      }
      Sim3Alignment a;
      std::string why;
      if (ComputeAlignment(p_e, p_g, AlignmentType::kSim3, &a, &why) && a.scale > 0.0) {
        ScaleSegment s;
        s.first_pair = begin;
        s.last_pair = end - 1;
        s.from_m = distance[begin];
        s.to_m = distance[end - 1];
        s.relative_scale = result.alignment.scale / a.scale;
        out.segments.push_back(s);
      }
    }
    // The next segment starts at this one's last pair: the segments share their ends.
    begin = end > begin ? end - 1 : begin;
  }
  if (out.segments.empty()) {
    out.note = "no segment with 3 poses and a measurable path";
    return out;
  }
  const auto [lo, hi] = std::minmax_element(
      out.segments.begin(), out.segments.end(),
      [](const ScaleSegment& a, const ScaleSegment& b) { return a.relative_scale < b.relative_scale; });
  out.min = lo->relative_scale;
  out.max = hi->relative_scale;
  return out;
}

nlohmann::json ScaleAlongPathToJson(const ScaleAlongPath& scale) {
  nlohmann::json segments = nlohmann::json::array();
  for (const ScaleSegment& s : scale.segments) {
    segments.push_back({{"from_m", s.from_m}, {"to_m", s.to_m}, {"scale", s.relative_scale}});
  }
  nlohmann::json j = {{"segment_m", scale.segment_m},
                      {"min", scale.min},
                      {"max", scale.max},
                      {"segments", std::move(segments)}};
  if (!scale.note.empty()) j["note"] = scale.note;
  return j;
}

}  // namespace dala
