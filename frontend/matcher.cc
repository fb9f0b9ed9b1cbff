#include "frontend/matcher.h"

#include <glog/logging.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <complex>
#include <deque>
#include <limits>
#include <memory>

#include "frontend/match_geometry.h"
#include "frontend/spatial_grid.h"

namespace dala {

bool MatcherOptions::IsValid(std::string* why) const {
  auto fail = [&](const std::string& msg) {
    if (why != nullptr) *why = msg;
    return false;
  };
  if (!(min_zncc > -1.0 && min_zncc < 1.0)) return fail("min_zncc must be in (-1, 1)");
  if (top_k < 1) return fail("top_k must be >= 1");
  if (!(max_scale_ratio >= 1.0)) return fail("max_scale_ratio must be >= 1");
  if (!(max_rotation > 0.0)) return fail("max_rotation must be > 0");
  if (!(max_eigen_ratio_change >= 1.0)) return fail("max_eigen_ratio_change must be >= 1");
  if (num_neighbours < 1) return fail("num_neighbours must be >= 1");
  if (min_support < 0) return fail("min_support must be >= 0");
  if (!(loose_angle > 0.0)) return fail("loose_angle must be > 0");
  if (!(loose_scale >= 1.0)) return fail("loose_scale must be >= 1");
  if (!(max_scale_mismatch >= 1.0)) return fail("max_scale_mismatch must be >= 1");
  if (!(position_tolerance_px > 0.0) || !(position_tolerance_rel >= 0.0))
    return fail("position_tolerance_px must be > 0 and position_tolerance_rel >= 0");
  if (!(propagation_min_zncc > -1.0 && propagation_min_zncc < 1.0))
    return fail("propagation_min_zncc must be in (-1, 1)");
  if (!(propagation_radius_px > 0.0) || !(propagation_radius_rel >= 0.0))
    return fail("propagation_radius_px must be > 0 and propagation_radius_rel >= 0");
  if (!(epipolar_max_dv >= 0.0)) return fail("epipolar_max_dv must be >= 0");
  if (!(min_disparity <= max_disparity)) return fail("min_disparity must be <= max_disparity");
  if (!(ransac_threshold_px > 0.0)) return fail("ransac_threshold_px must be > 0");
  if (!(ransac_confidence > 0.0 && ransac_confidence < 1.0))
    return fail("ransac_confidence must be in (0, 1)");
  if (ransac_max_iterations < 1) return fail("ransac_max_iterations must be >= 1");
  return true;
}

MatcherOptions MatcherOptions::ForStereo() {
  MatcherOptions o;
  o.max_scale_ratio = 1.5;
  o.max_rotation = 0.6;
  o.min_zncc = 0.75;
  o.geometric_check = GeometricCheck::kEpipolarRectified;
  return o;
}

MatcherOptions MatcherOptions::ForTracking() {
  MatcherOptions o;
  o.max_scale_ratio = 1.6;
  o.max_rotation = 0.8;
  o.min_zncc = 0.75;
  o.geometric_check = GeometricCheck::kFundamental;
  return o;
}

MatchPrior MatchPrior::RectifiedStereo(double max_dv, double min_disparity, double max_disparity) {
  MatchPrior p;
  p.type = Type::kRectifiedStereo;
  p.max_dv = max_dv;
  p.min_disparity = min_disparity;
  p.max_disparity = max_disparity;
  return p;
}

MatchPrior MatchPrior::Predicted(std::vector<Eigen::Vector2d> predicted_uv, double radius) {
  MatchPrior p;
  p.type = Type::kPredicted;
  p.predicted_uv = std::move(predicted_uv);
  p.radius = radius;
  return p;
}

bool MatchPrior::Allows(const Eigen::Vector2d& uv_a, int i, const Eigen::Vector2d& uv_b) const {
  switch (type) {
    case Type::kNone:
      return true;
    case Type::kRectifiedStereo: {
      const double d = uv_a.x() - uv_b.x();
      return std::abs(uv_a.y() - uv_b.y()) <= max_dv && d >= min_disparity && d <= max_disparity;
    }
    case Type::kPredicted: {
      const Eigen::Vector2d& p = predicted_uv[i];
      if (!p.allFinite()) return false;
      return (uv_b - p).squaredNorm() <= radius * radius;
    }
  }
  return false;
}

namespace {

constexpr double kPi = 3.14159265358979323846;

double WrapAngle(double a) {
  a = std::fmod(a + kPi, 2.0 * kPi);
  if (a < 0.0) a += 2.0 * kPi;
  return a - kPi;
}

double Median(std::vector<double> v) {
  const size_t mid = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + mid, v.end());
  return v[mid];
}

struct Candidate {
  int j;
  float score;
};

// A match with the local similarity (rotation phi, scale sigma) that maps A offsets to B offsets
// around it: q' - q = sigma R(phi) (p' - p).
struct GroupMatch {
  int i, j;
  float score;
  int support;
  double phi, sigma;
};

class Matcher {
 public:
  Matcher(const DetectedImage& a, const DetectedImage& b, const MatcherOptions& options,
          const MatchPrior* prior)
      : a_(a), b_(b), o_(options), prior_(prior), na_(a.points.size()), nb_(b.points.size()) {}

  std::vector<Match> Run(MatchStats* stats) {
    std::vector<Match> result;
    if (na_ == 0 || nb_ == 0) return result;
    std::vector<Eigen::Vector2d> uv_a(na_), uv_b(nb_);
    for (size_t i = 0; i < na_; ++i) uv_a[i] = a_.points[i].uv;
    for (size_t j = 0; j < nb_; ++j) uv_b[j] = b_.points[j].uv;
    const double cell = 24.0;
    grid_b_ = std::make_unique<SpatialGrid>(uv_b, cell);
    FindCandidates();
    neighbour_lists_ = CachedNearestNeighbours(uv_a, o_.num_neighbours, a_.neighbour_cache.get());
    std::vector<GroupMatch> confirmed = Confirm();
    SelectOneToOne(&confirmed);
    const int num_confirmed = static_cast<int>(confirmed.size());
    if (o_.propagate) Propagate(&confirmed);
    std::sort(confirmed.begin(), confirmed.end(),
              [](const GroupMatch& l, const GroupMatch& r) { return l.i < r.i; });
    for (const GroupMatch& g : confirmed) result.push_back({g.i, g.j, g.score});
    bool failed = false;
    result = ApplyGeometricCheck(a_, b_, result, o_, &failed);
    if (stats != nullptr) {
      stats->candidates = num_candidates_;
      stats->confirmed = num_confirmed;
      stats->propagated = static_cast<int>(confirmed.size()) - num_confirmed;
      stats->after_check = static_cast<int>(result.size());
      stats->check_failed = failed;
    }
    return result;
  }

 private:
  // Attribute, scale, rotation and prior gates of a pair (cheap, before any correlation).
  bool Allowed(int i, int j) const {
    const InterestPoint& p = a_.points[i];
    const InterestPoint& q = b_.points[j];
    const double scale_ratio = q.scale > p.scale ? q.scale / p.scale : p.scale / q.scale;
    if (scale_ratio > o_.max_scale_ratio * 1.0001) return false;
    if (o_.max_rotation < kPi &&
        std::abs(WrapAngle(q.orientation - p.orientation)) > o_.max_rotation) {
      return false;
    }
    // lambda1/lambda2 is invariant to contrast and (roughly) to scale: a corner stays a corner.
    const double ra = p.lambda1 / std::max(p.lambda2, 1e-6f);
    const double rb = q.lambda1 / std::max(q.lambda2, 1e-6f);
    if (std::max(ra / rb, rb / ra) > o_.max_eigen_ratio_change) return false;
    if (prior_ != nullptr && !prior_->Allows(p.uv, i, q.uv)) return false;
    return true;
  }

  void FindCandidates() {
    const int d = a_.descriptors.cols;
    CHECK_EQ(d, b_.descriptors.cols) << "DetectedImages with different patch sizes";
    using RowMat = Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
    Eigen::Map<const RowMat> da(a_.descriptors.ptr<float>(), na_, d);
    Eigen::Map<const RowMat> db(b_.descriptors.ptr<float>(), nb_, d);
    // Dense ZNCC matrix when unconstrained; with a prior only the allowed pairs are scored.
    const bool dense = prior_ == nullptr || prior_->type == MatchPrior::Type::kNone;
    RowMat scores;
    if (dense) scores.noalias() = da * db.transpose();
    const float kNone = -2.f;
    auto score = [&](int i, int j) -> float {
      if (!Allowed(i, j)) return kNone;
      return dense ? scores(i, j) : da.row(i).dot(db.row(j));
    };
    std::vector<std::vector<Candidate>> from_a(na_), from_b(nb_);
    const float min_score = static_cast<float>(o_.min_zncc);
    auto push_top_k = [&](std::vector<Candidate>* list, Candidate c) {
      list->push_back(c);
      std::sort(list->begin(), list->end(), [](const Candidate& l, const Candidate& r) {
        return l.score > r.score || (l.score == r.score && l.j < r.j);
      });
      if (static_cast<int>(list->size()) > o_.top_k) list->pop_back();
    };
    // With a prior, only the B points in the allowed region are visited: around the prediction
    // (spatial grid) or in the row band of a rectified pair (B sorted by row). This keeps
    // tracking and stereo linear in the number of points instead of quadratic.
    std::vector<int> b_by_row(nb_);
    for (size_t j = 0; j < nb_; ++j) b_by_row[j] = static_cast<int>(j);
    const bool banded = prior_ != nullptr && prior_->type == MatchPrior::Type::kRectifiedStereo;
    if (banded) {
      std::sort(b_by_row.begin(), b_by_row.end(), [&](int l, int r) {
        return b_.points[l].uv.y() < b_.points[r].uv.y() ||
               (b_.points[l].uv.y() == b_.points[r].uv.y() && l < r);
      });
    }
    std::vector<int> region;
    auto region_of = [&](size_t i) -> const std::vector<int>& {
      region.clear();
      if (dense) {
        region = b_by_row;  // Identity order.
      } else if (banded) {
        const double v = a_.points[i].uv.y();
        auto lo = std::lower_bound(b_by_row.begin(), b_by_row.end(), v - prior_->max_dv,
                                   [&](int j, double x) { return b_.points[j].uv.y() < x; });
        for (auto it = lo; it != b_by_row.end() && b_.points[*it].uv.y() <= v + prior_->max_dv;
             ++it) {
          region.push_back(*it);
        }
        std::sort(region.begin(), region.end());
      } else {
        const Eigen::Vector2d& pred = prior_->predicted_uv[i];
        if (pred.allFinite()) region = grid_b_->InRadius(pred, prior_->radius);
        std::sort(region.begin(), region.end());
      }
      return region;
    };
    for (size_t i = 0; i < na_; ++i) {
      for (const int jj : region_of(i)) {
        const size_t j = static_cast<size_t>(jj);
        if (dense && scores(i, j) < min_score) continue;
        const float s = score(static_cast<int>(i), static_cast<int>(j));
        if (s < min_score) continue;
        auto& la = from_a[i];
        if (static_cast<int>(la.size()) < o_.top_k || s > la.back().score) {
          push_top_k(&la, {static_cast<int>(j), s});
        }
        auto& lb = from_b[j];
        if (static_cast<int>(lb.size()) < o_.top_k || s > lb.back().score) {
          push_top_k(&lb, {static_cast<int>(i), s});
        }
      }
    }
    // Union of both directions, per A point, sorted by j.
    candidates_.assign(na_, {});
    for (size_t i = 0; i < na_; ++i) candidates_[i] = from_a[i];
    for (size_t j = 0; j < nb_; ++j) {
      for (const Candidate& c : from_b[j]) {
        auto& l = candidates_[c.j];
        const bool present = std::any_of(
            l.begin(), l.end(), [&](const Candidate& x) { return x.j == static_cast<int>(j); });
        if (!present) l.push_back({static_cast<int>(j), c.score});
      }
    }
    num_candidates_ = 0;
    for (auto& l : candidates_) {
      std::sort(l.begin(), l.end(),
                [](const Candidate& x, const Candidate& y) { return x.j < y.j; });
      num_candidates_ += static_cast<int>(l.size());
    }
  }

  // Group consistency of candidate (i, j): returns false or fills the match and its similarity.
  bool ConfirmOne(int i, const Candidate& c, GroupMatch* out) const {
    const InterestPoint& p = a_.points[i];
    const InterestPoint& q = b_.points[c.j];
    const double theta0 = WrapAngle(q.orientation - p.orientation);
    const double log_s0 = std::log(q.scale / p.scale);
    // The pair's own guess as a complex number z0 = s0 e^{i theta0}; a neighbour vector pair
    // (d_a, d_b) defines z = d_b / d_a, and w = z / z0 must be close to 1: |arg w| below
    // loose_angle and |log |w|| below log(loose_scale) (tested without trigonometry).
    const std::complex<double> z0 = std::polar(std::exp(log_s0), theta0);
    const double cos_loose = std::cos(o_.loose_angle);
    const double loose2 = o_.loose_scale * o_.loose_scale;
    struct Vote {
      Eigen::Vector2d d_a, q_b;
      double dphi, log_s;
    };
    std::vector<Vote> votes;
    for (int n : (*neighbour_lists_)[i]) {
      const Eigen::Vector2d d_a = a_.points[n].uv - p.uv;
      const double len2_a = d_a.squaredNorm();
      if (len2_a < 1.0) continue;
      const InterestPoint& pn = a_.points[n];
      const std::complex<double> za(d_a.x(), d_a.y());
      bool found = false;
      std::complex<double> best_w;
      Eigen::Vector2d best_q;
      float best_score = -2.f;
      for (const Candidate& cn : candidates_[n]) {
        if (cn.j == c.j || cn.score <= best_score) continue;
        const InterestPoint& qn = b_.points[cn.j];
        const Eigen::Vector2d d_b = qn.uv - q.uv;
        const std::complex<double> w = std::complex<double>(d_b.x(), d_b.y()) / (za * z0);
        const double abs2_w = std::norm(w);
        if (abs2_w > loose2 || abs2_w * loose2 < 1.0) continue;
        if (w.real() < cos_loose * std::sqrt(abs2_w)) continue;
        if (std::abs(WrapAngle(qn.orientation - pn.orientation - theta0)) > o_.loose_angle) {
          continue;
        }
        found = true;
        best_score = cn.score;
        best_w = w;
        best_q = qn.uv;
      }
      if (found) {
        votes.push_back(
            {d_a, best_q, std::arg(best_w), log_s0 + 0.5 * std::log(std::norm(best_w))});
      }
    }
    if (static_cast<int>(votes.size()) < o_.min_support) return false;
    double phi = theta0, log_s = log_s0;
    if (!votes.empty()) {
      std::vector<double> dphis, log_ss;
      for (const Vote& v : votes) {
        dphis.push_back(v.dphi);
        log_ss.push_back(v.log_s);
      }
      phi = theta0 + Median(dphis);
      log_s = Median(log_ss);
    }
    const double sigma = std::exp(log_s);
    const Eigen::Matrix2d sR =
        sigma * (Eigen::Matrix2d() << std::cos(phi), -std::sin(phi), std::sin(phi), std::cos(phi))
                    .finished();
    int support = 0;
    for (const Vote& v : votes) {
      const Eigen::Vector2d predicted = q.uv + sR * v.d_a;
      const double tol =
          o_.position_tolerance_px + o_.position_tolerance_rel * (predicted - q.uv).norm();
      if ((v.q_b - predicted).norm() <= tol) ++support;
    }
    if (support < o_.min_support) return false;
    if (std::abs(log_s0 - log_s) > std::log(o_.max_scale_mismatch)) return false;
    *out = {i, c.j, c.score, support, WrapAngle(phi), sigma};
    return true;
  }

  std::vector<GroupMatch> Confirm() const {
    std::vector<GroupMatch> confirmed;
    for (size_t i = 0; i < na_; ++i) {
      for (const Candidate& c : candidates_[i]) {
        GroupMatch g;
        if (ConfirmOne(static_cast<int>(i), c, &g)) confirmed.push_back(g);
      }
    }
    return confirmed;
  }

  void SelectOneToOne(std::vector<GroupMatch>* matches) {
    std::sort(matches->begin(), matches->end(), [](const GroupMatch& l, const GroupMatch& r) {
      if (l.support != r.support) return l.support > r.support;
      if (l.score != r.score) return l.score > r.score;
      return l.i < r.i || (l.i == r.i && l.j < r.j);
    });
    used_a_.assign(na_, false);
    used_b_.assign(nb_, false);
    std::vector<GroupMatch> kept;
    for (const GroupMatch& g : *matches) {
      if (used_a_[g.i] || used_b_[g.j]) continue;
      used_a_[g.i] = used_b_[g.j] = true;
      kept.push_back(g);
    }
    *matches = std::move(kept);
  }

  // Breadth-first growth from the matches, guided by their local similarity.
  void Propagate(std::vector<GroupMatch>* matches) {
    const int n = a_.patch_size * a_.patch_size;
    std::vector<float> patch(n);
    std::deque<size_t> queue;
    const double log_mismatch = std::log(o_.max_scale_mismatch);
    for (size_t k = 0; k < matches->size(); ++k) queue.push_back(k);
    while (!queue.empty()) {
      const GroupMatch g = (*matches)[queue.front()];
      queue.pop_front();
      const Eigen::Vector2d& p = a_.points[g.i].uv;
      const Eigen::Vector2d& q = b_.points[g.j].uv;
      const Eigen::Matrix2d sR = g.sigma * (Eigen::Matrix2d() << std::cos(g.phi), -std::sin(g.phi),
                                            std::sin(g.phi), std::cos(g.phi))
                                               .finished();
      for (int nbr : (*neighbour_lists_)[g.i]) {
        if (used_a_[nbr]) continue;
        const InterestPoint& pn = a_.points[nbr];
        const Eigen::Vector2d predicted = q + sR * (pn.uv - p);
        const double radius =
            o_.propagation_radius_px + o_.propagation_radius_rel * (predicted - q).norm();
        const float* desc_a = a_.descriptors.ptr<float>(nbr);
        int best_j = -1;
        float best = static_cast<float>(o_.propagation_min_zncc);
        for (int j : grid_b_->InRadius(predicted, radius)) {
          if (used_b_[j]) continue;
          if (std::abs(std::log(b_.points[j].scale / (pn.scale * g.sigma))) > log_mismatch) {
            continue;
          }
          if (prior_ != nullptr && !prior_->Allows(pn.uv, nbr, b_.points[j].uv)) continue;
          // B patch resampled with the group's rotation and scale around the B point.
          if (!SamplePatch(b_, b_.points[j].uv, pn.orientation + g.phi, pn.scale * g.sigma,
                           patch.data())) {
            continue;
          }
          float zncc = 0.f;
          for (int t = 0; t < n; ++t) zncc += desc_a[t] * patch[t];
          if (zncc > best) {
            best = zncc;
            best_j = j;
          }
        }
        if (best_j < 0) continue;
        used_a_[nbr] = used_b_[best_j] = true;
        matches->push_back({nbr, best_j, best, 0, g.phi, g.sigma});
        queue.push_back(matches->size() - 1);
      }
    }
  }

  const DetectedImage& a_;
  const DetectedImage& b_;
  const MatcherOptions& o_;
  const MatchPrior* prior_;
  const size_t na_, nb_;
  std::vector<std::vector<Candidate>> candidates_;  // Per A point, sorted by j.
  int num_candidates_ = 0;
  std::unique_ptr<SpatialGrid> grid_b_;
  std::shared_ptr<const NeighbourLists> neighbour_lists_;  // k nearest A points of each A point.
  std::vector<bool> used_a_, used_b_;
};

}  // namespace

std::vector<Match> MatchPoints(const DetectedImage& a, const DetectedImage& b,
                               const MatcherOptions& options, const MatchPrior* prior,
                               MatchStats* stats) {
  std::string why;
  CHECK(options.IsValid(&why)) << "Invalid MatcherOptions: " << why;
  if (prior != nullptr && prior->type == MatchPrior::Type::kPredicted) {
    CHECK_EQ(prior->predicted_uv.size(), a.points.size())
        << "MatchPrior::predicted_uv must have one entry per point of image A";
  }
  CHECK_EQ(a.descriptors.rows, static_cast<int>(a.points.size()));
  CHECK_EQ(b.descriptors.rows, static_cast<int>(b.points.size()));
  if (stats != nullptr) *stats = MatchStats();
  Matcher matcher(a, b, options, prior);
  return matcher.Run(stats);
}

}  // namespace dala
