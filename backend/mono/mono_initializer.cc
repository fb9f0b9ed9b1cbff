#include "backend/mono/mono_initializer.h"

#include <glog/logging.h>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <unordered_map>

#include "backend/ba/ba_types.h"
#include "backend/mono/refined_two_view.h"
#include "core/cv_pose.h"

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
  if (!(next_frame_min_inlier_ratio >= 0.0 && next_frame_min_inlier_ratio <= 1.0))
    return fail("mono_init.next_frame_min_inlier_ratio must be in [0, 1]");
  return true;
}

std::string MonoInitialization::ModelName() const {
  return std::string(TwoViewModelName(two_view.model)) + (magsac ? " (MAGSAC++)" : "");
}

MonoInitializer::Correspondences MonoInitializer::Correspond(const FrameMeasurement& reference,
                                                             const FrameMeasurement& m) {
  std::unordered_map<LandmarkId, size_t> in_reference;
  for (size_t i = 0; i < reference.observations.size(); ++i) {
    in_reference.emplace(reference.observations[i].landmark, i);
  }
  Correspondences c;
  for (const FeatureObservation& o : m.observations) {
    const auto it = in_reference.find(o.landmark);
    if (it == in_reference.end()) continue;
    c.uv_ref.push_back(reference.observations[it->second].uv);
    c.uv_cur.push_back(o.uv);
    c.ids.push_back(o.landmark);
  }
  return c;
}

MonoInitializer::MonoInitializer(const PinholeCamera& camera, const MonoInitializerOptions& options)
    : camera_(camera), options_(options) {
  std::string why;
  CHECK(options_.IsValid(&why)) << why;
}

void MonoInitializer::Reset() {
  reference_.reset();
  between_.clear();
  earlier_.clear();
  pair_.reset();
  reason_.clear();
}

void MonoInitializer::GiveUp(size_t count) {
  if (!reference_) return;
  earlier_.push_back(std::move(*reference_));
  reference_.reset();
  for (size_t k = 0; k < count && k < between_.size(); ++k) {
    earlier_.push_back(std::move(between_[k]));
  }
  while (earlier_.size() > kMaxEarlierFrames) earlier_.pop_front();
}

std::optional<MonoInitialization> MonoInitializer::TryPair(const FrameMeasurement& reference,
                                                           const FrameMeasurement& m,
                                                           const Correspondences& c,
                                                           std::string* why_not) const {
  RefinedTwoView solved =
      SolveRefinedTwoView(camera_, c.uv_ref, c.uv_cur, options_.two_view, options_.refine);
  if (!solved.two_view.ok) {
    *why_not = solved.two_view.reason + " (reference frame " +
               std::to_string(reference.frame.value) + ", " + std::to_string(c.ids.size()) +
               " tracks, " + TwoViewModelName(solved.two_view.model) + ")";
    return std::nullopt;
  }
  const std::vector<std::optional<Eigen::Vector3d>>& p_ref = solved.p_ref;
  const int good = static_cast<int>(
      std::count_if(p_ref.begin(), p_ref.end(), [](const auto& p) { return p.has_value(); }));
  if (good < options_.two_view.min_points) {
    *why_not = "too few points after the two-view refinement: " + std::to_string(good) + " < " +
               std::to_string(options_.two_view.min_points);
    return std::nullopt;
  }
  MonoInitialization init;
  init.reference = reference;
  init.current = m;
  init.T_ref_cur = solved.T_cur_ref.inverse();
  for (size_t i = 0; i < c.ids.size(); ++i) {
    if (p_ref[i]) init.p_ref[c.ids[i]] = *p_ref[i];
  }
  init.two_view = std::move(solved.two_view);
  init.magsac = solved.magsac;
  return init;
}

namespace {

// The next-frame check needs at least this many of the pair's points in the frame (a PnP's
// sample plus a few to vote).
constexpr int kMinObservedToCheck = 6;

}  // namespace

double MonoInitializer::NextFrameInlierRatio(const MonoInitialization& pair,
                                             const FrameMeasurement& m, int* observed) const {
  std::vector<Eigen::Vector3d> p_ref;
  std::vector<Eigen::Vector2d> uv;
  for (const FeatureObservation& o : m.observations) {
    const auto it = pair.p_ref.find(o.landmark);
    if (it == pair.p_ref.end()) continue;
    p_ref.push_back(it->second);
    uv.push_back(o.uv);
  }
  *observed = static_cast<int>(p_ref.size());
  if (*observed < kMinObservedToCheck) return 0.0;
  // The chi-square 95 % bound of a 1-pixel observation (2 dof), as the window's tracking.
  const PnpRansacResult pnp = SeededPnpRansac(p_ref, uv, camera_.K(),
                                              std::sqrt(kChi2Quantile95Dof2),
                                              options_.two_view.ransac_order_seed);
  return pnp.found ? static_cast<double>(pnp.inliers) / *observed : 0.0;
}

std::optional<MonoInitialization> MonoInitializer::Add(const FrameMeasurement& m) {
  std::string dropped;  // Why a waiting pair was dropped at m, if one was.
  if (pair_) {
    int observed = 0;
    const double ratio = NextFrameInlierRatio(*pair_, m, &observed);
    VLOG(1) << "first pair " << pair_->reference.frame << "-" << pair_->current.frame
            << ": frame " << m.frame << " keeps " << ratio << " of " << observed << " points";
    // A frame that sees too few of the pair's points (blank, blurred) is no evidence against
    // it: the map starts as it would without the check, and that frame is tracked in it.
    if (observed < kMinObservedToCheck || ratio >= options_.next_frame_min_inlier_ratio) {
      MonoInitialization init = std::move(*pair_);
      init.next = m;
      Reset();
      reason_ = "initialised";
      return init;
    }
    // Dropped: the initialiser goes on from the pair's reference (after the lost-reference
    // path of FindPair, the frame between it chose; the frames before it stay earlier), the
    // pair's current frame now one of the frames between the reference and m.
    std::ostringstream why;
    why.precision(2);
    why << "the pair of frames " << pair_->reference.frame << " and " << pair_->current.frame
        << " failed the next frame's check (" << ratio << " of " << observed
        << " points kept; ";
    dropped = why.str();
    MonoInitialization& pair = *pair_;
    reference_ = std::move(pair.reference);
    between_ = std::move(pair.between);
    between_.push_back(std::move(pair.current));
    earlier_.assign(std::make_move_iterator(pair.earlier.begin()),
                    std::make_move_iterator(pair.earlier.end()));
    pair_.reset();
  }
  std::optional<MonoInitialization> found = FindPair(m);
  if (found && options_.next_frame_min_inlier_ratio > 0.0) {
    pair_ = std::move(found);
    found.reset();  // It waits for the next frame.
    reason_ = "checking the pair of frames " + std::to_string(pair_->reference.frame.value) +
              " and " + std::to_string(m.frame.value) + " against the next frame";
  }
  if (!dropped.empty()) reason_ = dropped + reason_ + ")";
  return found;
}

std::optional<MonoInitialization> MonoInitializer::TakeWaitingPair() {
  if (!pair_) return std::nullopt;
  std::optional<MonoInitialization> pair = std::move(pair_);
  Reset();
  reason_ = "initialised";
  return pair;
}

std::optional<MonoInitialization> MonoInitializer::FindPair(const FrameMeasurement& m) {
  const auto start_reference = [&](const std::string& why) {
    GiveUp(between_.size());
    between_.clear();
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
  const auto initialised = [&](MonoInitialization init) {
    init.earlier.assign(std::make_move_iterator(earlier_.begin()),
                        std::make_move_iterator(earlier_.end()));
    Reset();
    reason_ = "initialised";
    return std::optional<MonoInitialization>(std::move(init));
  };
  if (!reference_) return start_reference("");

  const Correspondences with_reference = Correspond(*reference_, m);
  if (static_cast<int>(with_reference.ids.size()) < options_.two_view.min_points) {
    std::ostringstream os;
    os << "lost the reference frame " << reference_->frame << " (" << with_reference.ids.size()
       << " tracks left)";
    // Before the current frame becomes the reference: the oldest frame since then that still
    // shares a reference's worth of landmarks (min_reference_features) with it is tried as the
    // reference of this frame (the widest baseline left), and kept if the pair initialises
    // now. Moving fast forward, a reference loses its tracks within two or three frames while
    // one frame of motion has too little parallax; a frame between then still has both. A pair
    // that does not initialise at once is not kept: the current frame, with all its tracks, is
    // the better reference for the next frames.
    for (size_t k = 0; k < between_.size(); ++k) {
      const Correspondences with_frame = Correspond(between_[k], m);
      if (static_cast<int>(with_frame.ids.size()) < options_.min_reference_features) continue;
      std::string why_not;
      std::optional<MonoInitialization> init = TryPair(between_[k], m, with_frame, &why_not);
      if (init) {
        init->between.assign(std::make_move_iterator(between_.begin() + k + 1),
                             std::make_move_iterator(between_.end()));
        GiveUp(k);  // The old reference and the frames before between_[k].
        return initialised(std::move(*init));
      }
      os << "; frame " << between_[k].frame << " as the reference: " << why_not;
      break;
    }
    return start_reference(os.str());
  }
  if (static_cast<int>(between_.size()) >= options_.max_pending_frames) {
    std::ostringstream os;
    os << "no initialisation within " << options_.max_pending_frames << " frames of frame "
       << reference_->frame;
    return start_reference(os.str());
  }
  std::optional<MonoInitialization> init = TryPair(*reference_, m, with_reference, &reason_);
  if (!init) {
    between_.push_back(m);
    return std::nullopt;
  }
  init->between = std::move(between_);
  return initialised(std::move(*init));
}

}  // namespace dala
