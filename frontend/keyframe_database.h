#ifndef DALA_FRONTEND_KEYFRAME_DATABASE_H_
#define DALA_FRONTEND_KEYFRAME_DATABASE_H_

// KeyframeDatabase: what the frontend remembers of every keyframe so that a place can be
// recognised when the camera comes back (frontend/place_recognition.h).
//
// An entry is a plain struct (the coordinator serialises the database with the map): the
// keyframe's identity, its dead-reckoned pose (the frontend's visual odometry, used by the
// place-recognition spatial gate), its global appearance descriptor, and its points that have a
// stereo depth (the only ones a PnP can use): position, landmark id, normalised patch, and the
// stereo point in the keyframe's left camera with its covariance.
//
// Memory: ~0.13 MB per keyframe with 500 stereo points (11x11 patches at 8 bits,
// core/quantized_descriptors.h; 0.3 MB as floats); the image pyramid is NOT kept (the
// matcher only resamples patches in its second image, the current frame), nor the matcher's
// neighbour lists (Detection() builds the matcher's input at each verification).
//
// Not thread-safe.

#include <cstdint>
#include <deque>
#include <optional>
#include <unordered_map>
#include <vector>

#include <opencv2/core.hpp>

#include "core/geometry.h"
#include "core/quantized_descriptors.h"
#include "core/types.h"
#include "frontend/harris.h"
#include "frontend/stereo.h"

namespace dala {

struct KeyframeEntry {
  FrameId frame;
  int64_t t_ns = 0;
  // Dead-reckoned pose of the left camera (frontend visual odometry) and the dead-reckoned path
  // length from the first frame to this keyframe (metres).
  Pose T_w_c = Pose::Identity();
  double path_length_m = 0.0;
  // Global appearance descriptor (see place_recognition.h): CV_32F, z-normalised thumbnail.
  cv::Mat global_descriptor;
  // The stereo points: points[k] and descriptors' row k go with landmark[k] and stereo[k]. One
  // camera: points with a landmark id, stereo[k] the mapped landmark's point in this camera (the
  // map's unit) or empty.
  std::vector<InterestPoint> points;
  QuantizedDescriptors descriptors;
  std::vector<LandmarkId> landmark;
  std::vector<std::optional<StereoPoint>> stereo;
  // Of the keyframe's detection (what the matcher needs to resample patches around a point).
  cv::Size image_size;
  int patch_size = 11;
  double patch_spacing = 1.5;

  size_t size() const { return landmark.size(); }
  // The points as the matcher takes them: descriptors expanded to floats, no pyramid.
  DetectedImage Detection() const;
};

// Replaces every id of *ids that `new_id` maps (id now -> new id); the others stay.
void RenameLandmarkIds(const std::unordered_map<LandmarkId, LandmarkId>& new_id,
                       std::vector<LandmarkId>* ids);

class KeyframeDatabase {
 public:
  // Appends an entry (keyframes in time order: CHECKs that frame ids increase and that the
  // per-point vectors have one element per point).
  void Add(KeyframeEntry entry);

  const std::deque<KeyframeEntry>& entries() const { return entries_; }
  size_t size() const { return entries_.size(); }
  bool empty() const { return entries_.empty(); }
  // nullptr when `frame` is not a keyframe of the database.
  const KeyframeEntry* Find(FrameId frame) const;
  // The position of `frame`'s entry in entries(), or nullopt.
  std::optional<size_t> IndexOf(FrameId frame) const;
  // Gives the points of `frame`'s entry other landmark ids (`new_id`: id now -> id then); false
  // when `frame` has no entry.
  bool RenameLandmarks(FrameId frame, const std::unordered_map<LandmarkId, LandmarkId>& new_id);
  void Clear() { entries_.clear(); }

 private:
  // A deque, not a vector: an entry cannot be moved without a copy (cv::Mat's move constructor
  // is not noexcept in OpenCV 4.6, so std::vector's growth would copy every entry's point
  // vectors, ~0.1 MB each, at each doubling: steps of 15-100 MB of heap and a frame that copies
  // them, seen on the 3000-frame rover loop). Entries stay where they are; references to them
  // stay valid when more are added.
  std::deque<KeyframeEntry> entries_;
};

}  // namespace dala

#endif  // DALA_FRONTEND_KEYFRAME_DATABASE_H_
