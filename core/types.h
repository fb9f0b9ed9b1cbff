#ifndef DALA_CORE_TYPES_H_
#define DALA_CORE_TYPES_H_

// The shared vocabulary: strongly typed ids, the Frame a Dataset yields.
// (The FrameMeasurement message between frontend and estimators joins this file with the
// frontend; see DESIGN.md.)

#include <cstdint>
#include <functional>
#include <optional>
#include <ostream>

#include <opencv2/core.hpp>

#include "core/geometry.h"

namespace dala {

// An integer id that cannot be mixed up with an id of another kind: a FrameId is not a
// LandmarkId, even though both are int64 underneath. Ordered and hashable.
template <typename Tag>
struct Id {
  int64_t value = -1;

  constexpr Id() = default;
  constexpr explicit Id(int64_t v) : value(v) {}
  constexpr bool valid() const { return value >= 0; }
  constexpr bool operator==(const Id& o) const { return value == o.value; }
  constexpr bool operator!=(const Id& o) const { return value != o.value; }
  constexpr bool operator<(const Id& o) const { return value < o.value; }
};

template <typename Tag>
std::ostream& operator<<(std::ostream& os, const Id<Tag>& id) {
  return os << id.value;
}

struct FrameIdTag {};
struct KeyframeIdTag {};
struct LandmarkIdTag {};
using FrameId = Id<FrameIdTag>;
using KeyframeId = Id<KeyframeIdTag>;
using LandmarkId = Id<LandmarkIdTag>;

// One time step of a dataset: a grayscale image (left camera, rectified when the dataset is
// stereo) and, for stereo, the rectified right image. Images are CV_8UC1.
struct Frame {
  FrameId id;
  int64_t t_ns = 0;
  cv::Mat left;
  cv::Mat right;  // Empty for monocular datasets.
  // Ground-truth pose of the left (rectified) camera in the world, when the dataset has one.
  std::optional<Pose> T_w_c0_gt;
  // The left camera's pose by the dataset's odometry (a motion sensor, e.g. the odometry.txt of
  // `dala synth --odometry`), in the odometry's own world frame: only the relative motions
  // T_w_odom_prev^-1 T_w_odom_cur mean something.
  std::optional<Pose> T_w_odom;

  bool is_stereo() const { return !right.empty(); }
};

}  // namespace dala

namespace std {
template <typename Tag>
struct hash<dala::Id<Tag>> {
  size_t operator()(const dala::Id<Tag>& id) const { return std::hash<int64_t>()(id.value); }
};
}  // namespace std

#endif  // DALA_CORE_TYPES_H_
