#include "backend/mono/mono_initializer.h"

#include <glog/logging.h>

#include <algorithm>
#include <sstream>
#include <unordered_map>

#include "backend/mono/refined_two_view.h"

namespace dala {

bool MonoInitializerOptions::IsValid(std::string* why) const {
  if (!two_view.IsValid(why)) return false;
  const auto fail = [&](const char* msg) {
    if (why) *why = msg;
    return false;
  };
  if (min_reference_features < two_view.min_points)
    return fail("mono_init.min_reference_features must be >= mono_init.min_points");
  if (max_pending_frames < 1) return fail("mono_init.max_pending_frames must be >= 1");
  return true;
}

std::string MonoInitialization::ModelName() const {
  return std::string(TwoViewModelName(two_view.model)) + (magsac ? " (MAGSAC++)" : "");
}

MonoInitializer::MonoInitializer(const PinholeCamera& camera,
                                 const MonoInitializerOptions& options)
    : camera_(camera), options_(options) {
  std::string why;
  CHECK(options_.IsValid(&why)) << why;
}

void MonoInitializer::Reset() {
  reference_.reset();
  between_.clear();
  reason_.clear();
}

std::optional<MonoInitialization> MonoInitializer::Add(const FrameMeasurement& m) {
  const auto start_reference = [&](const std::string& why) {
    between_.clear();
    reference_.reset();
    const int n = static_cast<int>(m.observations.size());
    std::ostringstream os;
    if (n >= options_.min_reference_features) {
      reference_ = m;
      os << why << (why.empty() ? "" : "; ") << "frame " << m.frame << " is the new reference";
    } else {
      os << "no reference frame yet: " << n << " features < " << options_.min_reference_features;
    }
    reason_ = os.str();
    return std::nullopt;
  };
  if (!reference_) return start_reference("");

  // Correspondences: the landmarks the reference and the current frame both observe.
  std::unordered_map<LandmarkId, size_t> in_reference;
  for (size_t i = 0; i < reference_->observations.size(); ++i) {
    in_reference.emplace(reference_->observations[i].landmark, i);
  }
  std::vector<Eigen::Vector2d> uv_ref, uv_cur;
  std::vector<LandmarkId> ids;
  for (const FeatureObservation& o : m.observations) {
    const auto it = in_reference.find(o.landmark);
    if (it == in_reference.end()) continue;
    uv_ref.push_back(reference_->observations[it->second].uv);
    uv_cur.push_back(o.uv);
    ids.push_back(o.landmark);
  }
  if (static_cast<int>(ids.size()) < options_.two_view.min_points) {
    std::ostringstream os;
    os << "lost the reference frame " << reference_->frame << " (" << ids.size()
       << " tracks left)";
    return start_reference(os.str());
  }
  if (static_cast<int>(between_.size()) >= options_.max_pending_frames) {
    std::ostringstream os;
    os << "no initialisation within " << options_.max_pending_frames << " frames of frame "
       << reference_->frame;
    return start_reference(os.str());
  }

  RefinedTwoView solved =
      SolveRefinedTwoView(camera_, uv_ref, uv_cur, options_.two_view, options_.refine);
  if (!solved.two_view.ok) {
    reason_ = solved.two_view.reason + " (reference frame " +
              std::to_string(reference_->frame.value) + ", " + std::to_string(ids.size()) +
              " tracks, " + TwoViewModelName(solved.two_view.model) + ")";
    between_.push_back(m);
    return std::nullopt;
  }
  const std::vector<std::optional<Eigen::Vector3d>>& p_ref = solved.p_ref;
  const int good = static_cast<int>(std::count_if(p_ref.begin(), p_ref.end(),
                                                  [](const auto& p) { return p.has_value(); }));
  if (good < options_.two_view.min_points) {
    reason_ = "too few points after the two-view refinement: " + std::to_string(good) + " < " +
              std::to_string(options_.two_view.min_points);
    between_.push_back(m);
    return std::nullopt;
  }
  MonoInitialization init;
  init.reference = std::move(*reference_);
  init.between = std::move(between_);
  init.current = m;
  init.T_ref_cur = solved.T_cur_ref.inverse();
  for (size_t i = 0; i < ids.size(); ++i) {
    if (p_ref[i]) init.p_ref[ids[i]] = *p_ref[i];
  }
  init.two_view = std::move(solved.two_view);
  init.magsac = solved.magsac;
  Reset();
  reason_ = "initialised";
  return init;
}

}  // namespace dala
