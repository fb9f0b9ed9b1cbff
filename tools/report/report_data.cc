#include "tools/report/report_data.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <map>
#include <optional>

#include "core/eval/alignment.h"
#include "core/eval/scale_along_path.h"

namespace dala::report {
namespace {

// Rounded so that the JSON writer prints few digits (it prints the shortest exact form).
double Round(double v, double unit) { return std::round(v / unit) * unit; }

void AppendPosition(const Eigen::Vector3d& p, nlohmann::json* xyz) {
  for (int k = 0; k < 3; ++k) xyz->push_back(Round(p[k], 1e-3));
}

void AppendOrientation(const Pose& T, nlohmann::json* q) {
  const Eigen::Quaterniond r(T.linear());
  for (const double v : {r.x(), r.y(), r.z(), r.w()}) q->push_back(Round(v, 1e-4));
}

// The poses of a trajectory by time, to find a frame's pose from report.json's seconds (which
// carry the time as a double: nanoseconds of an EuRoC stamp are lost, so nearest within 0.5 ms).
class PoseLookup {
 public:
  explicit PoseLookup(const Trajectory& trajectory) {
    for (size_t i = 0; i < trajectory.size(); ++i) {
      t_s_.push_back(SecondsFromNs(trajectory.poses[i].t_ns));
    }
  }
  // The index of the pose at time t_s, or -1 when none is within 0.5 ms.
  int IndexAt(double t_s) const {
    const auto it = std::lower_bound(t_s_.begin(), t_s_.end(), t_s);
    int best = -1;
    double best_dt = 5e-4;
    for (auto c : {it, it == t_s_.begin() ? it : it - 1}) {
      if (c == t_s_.end()) continue;
      const double dt = std::abs(*c - t_s);
      if (dt <= best_dt) {
        best_dt = dt;
        best = static_cast<int>(c - t_s_.begin());
      }
    }
    return best;
  }
  // The pose at t_s, else the last one before it (-1: none before).
  int IndexAtOrBefore(double t_s) const {
    const int exact = IndexAt(t_s);
    if (exact >= 0) return exact;
    const auto it = std::upper_bound(t_s_.begin(), t_s_.end(), t_s);
    return it == t_s_.begin() ? -1 : static_cast<int>(it - t_s_.begin()) - 1;
  }
  size_t size() const { return t_s_.size(); }

 private:
  std::vector<double> t_s_;
};

double FrameTime(const nlohmann::json& frame) { return frame.value("t", 0.0); }

}  // namespace

std::vector<ReportKeyframe> KeyframesFromFrames(const nlohmann::json& frames,
                                                const Trajectory& trajectory) {
  std::vector<ReportKeyframe> keyframes;
  if (!frames.is_array()) return keyframes;
  const PoseLookup lookup(trajectory);
  for (const nlohmann::json& f : frames) {
    if (!f.value("keyframe", false)) continue;
    const int i = lookup.IndexAt(FrameTime(f));
    if (i < 0) continue;
    keyframes.push_back({f.value("frame", int64_t{-1}), trajectory.poses[i].T_w_c});
  }
  return keyframes;
}

nlohmann::json ReportDataJson(const ReportInput& input) {
  // The frame of reference: the ground truth's world when the evaluation succeeded.
  Sim3Alignment alignment;
  std::string reference = "the estimate's world (no ground truth)";
  const bool evaluated = input.evaluation && input.evaluation->ok && input.ground_truth;
  if (evaluated) {
    alignment = input.evaluation->alignment;
    reference = std::string("the ground truth's world; estimate aligned by ") +
                AlignmentTypeName(input.evaluation->options.alignment) + " (as dala eval)";
  } else if (input.evaluation && !input.evaluation->ok) {
    reference = "the estimate's world (evaluation not done: " + input.evaluation->error + ")";
  }
  const Trajectory path = AlignTrajectory(input.trajectory, alignment);
  const PoseLookup lookup(path);

  nlohmann::json data;
  data["title"] = input.title;
  data["frame_of_reference"] = reference;
  data["aspect"] = input.image_aspect;
  // Up: the first camera's -y axis (ground truth's when there is one).
  Eigen::Vector3d up(0, 0, 1);
  if (evaluated && !input.ground_truth->empty()) {
    up = -input.ground_truth->poses.front().T_w_c.linear().col(1);
  } else if (!path.empty()) {
    up = -path.poses.front().T_w_c.linear().col(1);
  } else if (!input.keyframes.empty()) {
    up = -input.keyframes.front().T_w_c.linear().col(1);
  }
  data["up"] = {Round(up.x(), 1e-4), Round(up.y(), 1e-4), Round(up.z(), 1e-4)};
  const double t0_s = path.empty() ? 0.0 : SecondsFromNs(path.poses.front().t_ns);
  data["t0"] = t0_s;

  // Map points, decimated above kMaxReportPoints.
  {
    const size_t total = input.points_w.size();
    const size_t stride =
        total > kMaxReportPoints ? (total + kMaxReportPoints - 1) / kMaxReportPoints : 1;
    nlohmann::json xyz = nlohmann::json::array();
    size_t shown = 0;
    for (size_t i = 0; i < total; i += stride) {
      AppendPosition(alignment.Apply(input.points_w[i]), &xyz);
      ++shown;
    }
    data["points"] = {{"xyz", std::move(xyz)}, {"shown", shown}, {"total", total}};
  }
  // The estimated path (aligned), with each pose's time from the first.
  {
    nlohmann::json t = nlohmann::json::array(), xyz = nlohmann::json::array(),
                   q = nlohmann::json::array();
    for (const StampedPose& p : path.poses) {
      t.push_back(Round(SecondsFromNs(p.t_ns) - t0_s, 1e-4));
      AppendPosition(p.T_w_c.translation(), &xyz);
      AppendOrientation(p.T_w_c, &q);
    }
    data["path"] = {{"t", std::move(t)}, {"xyz", std::move(xyz)}, {"q", std::move(q)}};
  }
  if (evaluated) {
    nlohmann::json xyz = nlohmann::json::array();
    for (const StampedPose& p : input.ground_truth->poses)
      AppendPosition(p.T_w_c.translation(), &xyz);
    data["ground_truth"] = {{"xyz", std::move(xyz)}};
    // The absolute error of each evaluated pose, against its time.
    const EvalResult& e = *input.evaluation;
    nlohmann::json t = nlohmann::json::array(), m = nlohmann::json::array();
    // The time of pair i, from the run's first pose (none for a KITTI row out of range).
    const auto PairTime = [&](size_t i) -> std::optional<double> {
      int64_t t_ns = e.pairs.t_ns[i];
      if (e.pairs.by_index) {
        // KITTI files: the stamp is the estimate's row.
        if (t_ns < 0 || static_cast<size_t>(t_ns) >= input.trajectory.size()) return std::nullopt;
        t_ns = input.trajectory.poses[t_ns].t_ns;
      }
      return SecondsFromNs(t_ns) - t0_s;
    };
    for (size_t i = 0; i < e.pairs.size() && i < e.ate.translation_errors.size(); ++i) {
      const std::optional<double> t_s = PairTime(i);
      if (!t_s) continue;
      t.push_back(Round(*t_s, 1e-4));
      m.push_back(Round(e.ate.translation_errors[i], 1e-4));
    }
    data["error"] = {{"t", std::move(t)}, {"m", std::move(m)}};
    // The scale along the path (core/eval/scale_along_path.h), as a step per segment: the
    // estimate's size against the truth's, in percent off (0: the run's scale).
    nlohmann::json st = nlohmann::json::array(), sp = nlohmann::json::array();
    for (const ScaleSegment& seg : MeasureScaleAlongPath(e).segments) {
      for (const size_t pair : {seg.first_pair, seg.last_pair}) {
        const std::optional<double> t_s = PairTime(pair);
        if (!t_s) continue;
        st.push_back(Round(*t_s, 1e-4));
        sp.push_back(Round(100.0 * (seg.relative_scale - 1.0), 1e-3));
      }
    }
    if (!st.empty()) data["scale"] = {{"t", std::move(st)}, {"percent", std::move(sp)}};
  }
  // Keyframes.
  {
    nlohmann::json frame = nlohmann::json::array(), xyz = nlohmann::json::array(),
                   q = nlohmann::json::array();
    for (const ReportKeyframe& k : input.keyframes) {
      const Pose T = alignment.Apply(k.T_w_c);
      frame.push_back(k.frame);
      AppendPosition(T.translation(), &xyz);
      AppendOrientation(T, &q);
    }
    data["keyframes"] = {{"frame", std::move(frame)}, {"xyz", std::move(xyz)}, {"q", std::move(q)}};
  }
  // Per frame: the charts, lost and relocalised frames, loops.
  nlohmann::json charts = {
      {"t", nlohmann::json::array()},         {"frame", nlohmann::json::array()},
      {"features", nlohmann::json::array()},  {"tracked", nlohmann::json::array()},
      {"landmarks", nlohmann::json::array()}, {"keyframe", nlohmann::json::array()},
      {"ms", nlohmann::json::array()},        {"status", nlohmann::json::array()}};
  nlohmann::json lost = {{"frame", nlohmann::json::array()}, {"xyz", nlohmann::json::array()}};
  nlohmann::json relocalised = {{"frame", nlohmann::json::array()},
                                {"xyz", nlohmann::json::array()}};
  nlohmann::json loops = nlohmann::json::array();
  if (input.frames.is_array()) {
    std::map<int64_t, double> time_of_frame;
    for (const nlohmann::json& f : input.frames) {
      time_of_frame[f.value("frame", int64_t{-1})] = FrameTime(f);
    }
    bool previous_lost = false;
    for (const nlohmann::json& f : input.frames) {
      const double t = FrameTime(f);
      const int64_t frame = f.value("frame", int64_t{-1});
      const std::string status = f.value("status", std::string());
      const bool is_lost = status == "lost";
      charts["t"].push_back(Round(t - t0_s, 1e-4));
      charts["frame"].push_back(frame);
      charts["features"].push_back(f.value("features", 0));
      charts["tracked"].push_back(f.value("tracked", 0));
      charts["landmarks"].push_back(f.value("landmarks", 0));
      charts["keyframe"].push_back(f.value("keyframe", false) ? 1 : 0);
      // `dala run --draws`: the wall time of every draw, what the run took for the frame.
      const double ms = !f.contains("ms")               ? 0.0
                        : f["ms"].contains("all_draws") ? f["ms"].value("all_draws", 0.0)
                                                        : f["ms"].value("total", 0.0);
      charts["ms"].push_back(Round(ms, 1e-2));
      // 0 initialising, 1 tracking, 2 lost: the chart's colour band.
      charts["status"].push_back(is_lost ? 2 : status == "tracking" ? 1 : 0);
      const int at_or_before = lookup.IndexAtOrBefore(t);
      if (is_lost && at_or_before >= 0) {
        lost["frame"].push_back(frame);
        AppendPosition(path.poses[at_or_before].T_w_c.translation(), &lost["xyz"]);
      }
      const int at = lookup.IndexAt(t);
      if (!is_lost && previous_lost && at >= 0) {
        relocalised["frame"].push_back(frame);
        AppendPosition(path.poses[at].T_w_c.translation(), &relocalised["xyz"]);
      }
      previous_lost = is_lost;
      const auto old = f.find("loop_old_frame");
      if (f.value("loop", false) && old != f.end() && old->is_number_integer() && at >= 0) {
        const auto old_t = time_of_frame.find(old->get<int64_t>());
        const int old_at = old_t == time_of_frame.end() ? -1 : lookup.IndexAt(old_t->second);
        if (old_at >= 0) {
          nlohmann::json a = nlohmann::json::array(), b = nlohmann::json::array();
          AppendPosition(path.poses[at].T_w_c.translation(), &a);
          AppendPosition(path.poses[old_at].T_w_c.translation(), &b);
          loops.push_back({{"frame", frame},
                           {"old_frame", old->get<int64_t>()},
                           {"closed", f.value("loop_closed", false)},
                           {"a", std::move(a)},
                           {"b", std::move(b)}});
        }
      }
    }
  }
  data["charts"] = std::move(charts);
  data["lost"] = std::move(lost);
  data["relocalised"] = std::move(relocalised);
  data["loops"] = std::move(loops);
  data["summary"] = input.summary.is_null() ? nlohmann::json::object() : input.summary;
  data["summary_text"] = input.summary_text;
  return data;
}

}  // namespace dala::report
