// Replays a run's keyframe observations (its map.dmap) through the monocular sliding window, with
// the dataset's ground truth beside, to tell how much of a run's scale drift the window makes and
// how much the frontend's pixels carry. `dala run` writes the map; the dataset must have ground
// truth (a rendered `dala synth` sequence has it exactly).
//
//   window_replay MAP.dmap DATASET [MODE] [--seed N]
//
// MODE (the pixels the window gets; default frontend):
//   frontend          the frontend's pixels, as the run's window got them;
//   truth             each track's point triangulated with the true poses (DLT over all its
//                     keyframes), projected with the true poses: same tracks, exact pixels;
//   truth_noise=S     the same plus Gaussian noise of S px per coordinate (seeded by --seed);
//   split_jumps=J     the frontend's pixels, a track cut into two landmarks where its distance
//                     to its true point changes by more than J px from one keyframe to its next;
//   drop_far=T        the frontend's pixels, those farther than T px from their true point
//                     left out.
//
// The window: SequenceBaOptions (`dala run`'s), every keyframe in the map's order, sigma 1 px;
// the first two keyframes at the truth (the gauge and the scale), each later one started at the
// window's constant velocity. Prints the estimate's length over the truth's for each tenth of
// the keyframe path, and log(last tenth / first tenth): the scale drift along the run.
// The truth's modes need pixel-exact ground truth (a rendered sequence): KITTI's is off by more
// than a pixel over a track. docs/monocular.md ("Scale drift: the window and the images") has
// the measurements.

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <map>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "backend/ba/sliding_window_ba.h"
#include "backend/sliding_window_estimator.h"
#include "core/error.h"
#include "core/io/dataset.h"
#include "core/io/map_file.h"
#include "tests/backend/ba/window_keyframe_poses.h"

namespace dala {
namespace {

struct Mode {
  enum Kind { kFrontend, kTruth, kSplitJumps, kDropFar } kind = kFrontend;
  double value = 0.0;  // noise sigma, jump or distance threshold (px).
};

std::optional<Mode> ParseMode(const std::string& s) {
  const auto value_of = [&](const std::string& prefix) -> std::optional<double> {
    if (s.rfind(prefix, 0) != 0) return std::nullopt;
    char* end = nullptr;
    const double v = std::strtod(s.c_str() + prefix.size(), &end);
    if (*end != '\0' || !(v >= 0)) return std::nullopt;
    return v;
  };
  if (s == "frontend") return Mode{Mode::kFrontend, 0.0};
  if (s == "truth") return Mode{Mode::kTruth, 0.0};
  if (auto v = value_of("truth_noise=")) return Mode{Mode::kTruth, *v};
  if (auto v = value_of("split_jumps=")) return Mode{Mode::kSplitJumps, *v};
  if (auto v = value_of("drop_far=")) return Mode{Mode::kDropFar, *v};
  return std::nullopt;
}

struct ReplayKeyframe {
  Pose T_w_c_true;
  std::vector<BaObservation> observations;
};

// The map's keyframes with their true poses (nearest ground-truth time, within 1 ms).
std::vector<ReplayKeyframe> LoadKeyframes(const SavedMap& map, const Trajectory& truth) {
  std::vector<ReplayKeyframe> out;
  for (const SavedKeyframe& kf : map.keyframes) {
    const StampedPose* best = nullptr;
    for (const StampedPose& p : truth.poses) {
      if (!best || std::llabs(p.t_ns - kf.t_ns) < std::llabs(best->t_ns - kf.t_ns)) best = &p;
    }
    if (!best || std::llabs(best->t_ns - kf.t_ns) > 1000000) {
      throw Error() << "keyframe at t = " << kf.t_ns << " ns has no ground-truth pose";
    }
    ReplayKeyframe r;
    r.T_w_c_true = best->T_w_c;
    for (const SavedKeyframePoint& p : kf.points) {
      if (!p.landmark.valid()) continue;
      BaObservation o;
      o.landmark = p.landmark;
      o.uv = p.uv;
      o.sigma_px = 1.0;
      r.observations.push_back(o);
    }
    out.push_back(std::move(r));
  }
  return out;
}

// Each track's point triangulated with the true poses (tracks of two or more keyframes whose
// rays meet at 0.5 deg or more, in front of every camera by 0.05 m or more).
std::map<LandmarkId, Eigen::Vector3d> TruePoints(const StereoIntrinsics& K,
                                                 const std::vector<ReplayKeyframe>& kfs) {
  std::map<LandmarkId, std::pair<std::vector<Pose>, std::vector<Eigen::Vector2d>>> views;
  for (const ReplayKeyframe& kf : kfs) {
    for (const BaObservation& o : kf.observations) {
      views[o.landmark].first.push_back(kf.T_w_c_true);
      views[o.landmark].second.push_back(o.uv);
    }
  }
  std::map<LandmarkId, Eigen::Vector3d> out;
  for (const auto& [id, v] : views) {
    if (v.first.size() < 2) continue;
    if (auto p = TriangulateViews(K, v.first, v.second, 0.5, 0.05)) out[id] = *p;
  }
  return out;
}

// Rewrites the observations as the mode says. split_jumps: *steps counts a track's steps from
// one of its keyframes to the next, and the return value those cut.
int ApplyMode(const Mode& mode, const PinholeCamera& camera,
              const std::map<LandmarkId, Eigen::Vector3d>& p_true, unsigned seed,
              std::vector<ReplayKeyframe>* kfs, int* steps) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, 1.0);
  // split_jumps: per track, its last offset from the true point and its current piece.
  std::map<LandmarkId, std::pair<Eigen::Vector2d, int>> piece;
  int64_t next_id = 0;
  for (const auto& [id, p] : p_true) next_id = std::max(next_id, id.value + 1);
  std::map<std::pair<LandmarkId, int>, LandmarkId> piece_id;
  int cuts = 0;
  for (ReplayKeyframe& kf : *kfs) {
    std::vector<BaObservation> kept;
    for (BaObservation o : kf.observations) {
      const auto it = p_true.find(o.landmark);
      if (mode.kind == Mode::kFrontend) {
        kept.push_back(o);
        continue;
      }
      if (it == p_true.end()) continue;  // no true point: left out in every other mode.
      Eigen::Vector2d exact;
      camera.Project(kf.T_w_c_true.inverse() * it->second, &exact);  // in front (TruePoints).
      const Eigen::Vector2d offset = o.uv - exact;
      if (mode.kind == Mode::kTruth) {
        o.uv = exact;
        if (mode.value > 0) {
          const double du = noise(rng);  // in this order (argument order is unspecified).
          const double dv = noise(rng);
          o.uv += mode.value * Eigen::Vector2d(du, dv);
        }
      } else if (mode.kind == Mode::kDropFar) {
        if (offset.norm() > mode.value) continue;
      } else {  // kSplitJumps
        auto [p, inserted] = piece.emplace(o.landmark, std::make_pair(offset, 0));
        if (!inserted) {
          ++*steps;
          if ((offset - p->second.first).norm() > mode.value) {
            ++p->second.second;
            ++cuts;
          }
          p->second.first = offset;
        }
        if (p->second.second > 0) {
          const auto key = std::make_pair(o.landmark, p->second.second);
          auto [n, fresh] = piece_id.emplace(key, LandmarkId(next_id));
          if (fresh) ++next_id;
          o.landmark = n->second;
        }
      }
      kept.push_back(o);
    }
    kf.observations = std::move(kept);
  }
  return cuts;
}

// The window over the keyframes; returns every keyframe's final estimate (in order).
std::vector<Pose> Replay(const StereoIntrinsics& K, const std::vector<ReplayKeyframe>& kfs) {
  SlidingWindowBa ba(K, SequenceBaOptions());
  const auto pose_of = [&](size_t i) {
    return *ba.KeyframePose(KeyframeId(static_cast<int64_t>(i)));
  };
  for (size_t i = 0; i < kfs.size(); ++i) {
    BaKeyframe kf;
    kf.id = KeyframeId(static_cast<int64_t>(i));
    kf.t_ns = static_cast<int64_t>(i);
    kf.observations = kfs[i].observations;
    // The two previous keyframes are still in the window (it holds more than two).
    kf.T_w_c =
        i < 2 ? kfs[i].T_w_c_true : pose_of(i - 1) * (pose_of(i - 2).inverse() * pose_of(i - 1));
    ba.AddKeyframe(kf);
    ba.Optimize();
  }
  return testing::AllKeyframePoses(ba);
}

int Main(int argc, char** argv) {
  std::vector<std::string> args;
  unsigned seed = 1;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--seed" && i + 1 < argc) {
      seed = static_cast<unsigned>(std::strtoul(argv[++i], nullptr, 10));
    } else {
      args.push_back(a);
    }
  }
  if (args.size() < 2 || args.size() > 3) {
    std::fprintf(stderr,
                 "usage: window_replay MAP.dmap DATASET [frontend | truth | truth_noise=S | "
                 "split_jumps=J | drop_far=T] [--seed N]\n(see the head of "
                 "benchmarks/window_replay.cc)\n");
    return 2;
  }
  const std::optional<Mode> mode = ParseMode(args.size() == 3 ? args[2] : "frontend");
  if (!mode) {
    std::fprintf(stderr, "window_replay: unknown mode '%s'\n", args[2].c_str());
    return 2;
  }
  const SavedMap map = ReadMapFile(args[0]);
  DatasetOptions options;
  options.force_mono = true;
  const std::unique_ptr<Dataset> dataset = OpenDataset(args[1], options);
  if (!dataset->ground_truth()) throw Error() << args[1] << " has no ground truth";
  const PinholeCamera& cam = dataset->rig().left;
  const StereoIntrinsics K{cam.fx, cam.fy, cam.cx, cam.cy, 0.0};
  std::vector<ReplayKeyframe> kfs = LoadKeyframes(map, *dataset->ground_truth());
  if (kfs.size() < 21) throw Error() << args[0] << ": " << kfs.size() << " keyframes, need 21";
  const std::map<LandmarkId, Eigen::Vector3d> p_true = TruePoints(K, kfs);
  int steps = 0;
  const int cuts = ApplyMode(*mode, cam, p_true, seed, &kfs, &steps);
  const std::vector<Pose> est = Replay(K, kfs);

  const size_t tenth = (est.size() - 1) / 10;
  std::vector<double> scale;
  for (size_t s = 0; s < 10; ++s) {
    double estimated = 0.0, truth = 0.0;
    for (size_t i = s * tenth; i < (s + 1) * tenth; ++i) {
      estimated += (est[i + 1].translation() - est[i].translation()).norm();
      truth += (kfs[i + 1].T_w_c_true.translation() - kfs[i].T_w_c_true.translation()).norm();
    }
    scale.push_back(estimated / truth);
  }
  std::printf("scale per tenth:");
  for (double x : scale) std::printf(" %.3f", x);
  std::printf("\nlog(last / first) %+.4f  (%zu keyframes, %zu tracks with a true point",
              std::log(scale.back() / scale.front()), kfs.size(), p_true.size());
  if (mode->kind == Mode::kSplitJumps) std::printf("; %d of %d steps cut", cuts, steps);
  std::printf(")\n");
  return 0;
}

}  // namespace
}  // namespace dala

int main(int argc, char** argv) {
  try {
    return dala::Main(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "window_replay: %s\n", e.what());
    return 1;
  }
}
