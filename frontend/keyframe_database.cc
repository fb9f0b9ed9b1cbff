#include "frontend/keyframe_database.h"

#include <glog/logging.h>

#include <algorithm>

namespace dala {

void KeyframeDatabase::Add(KeyframeEntry entry) {
  CHECK(entries_.empty() || entries_.back().frame < entry.frame)
      << "KeyframeDatabase::Add: frame ids must increase (" << entry.frame << " after "
      << entries_.back().frame << ")";
  const size_t n = entry.landmark.size();
  CHECK_EQ(entry.points.size(), n) << "one point per landmark id";
  CHECK_EQ(entry.stereo.size(), n) << "one stereo point per landmark id";
  CHECK_EQ(static_cast<size_t>(entry.descriptors.rows()), n) << "one descriptor per point";
  // The vectors were grown by push_back (up to twice the memory they need); entries live for the
  // whole run.
  entry.points.shrink_to_fit();
  entry.descriptors.shrink_to_fit();
  entry.landmark.shrink_to_fit();
  entry.stereo.shrink_to_fit();
  entries_.push_back(std::move(entry));
}

DetectedImage KeyframeEntry::Detection() const {
  DetectedImage d;
  d.points = points;
  d.descriptors = descriptors.Expand();
  d.image_size = image_size;
  d.patch_size = patch_size;
  d.patch_spacing = patch_spacing;
  return d;
}

const KeyframeEntry* KeyframeDatabase::Find(FrameId frame) const {
  const std::optional<size_t> i = IndexOf(frame);
  return i ? &entries_[*i] : nullptr;
}

std::optional<size_t> KeyframeDatabase::IndexOf(FrameId frame) const {
  const auto it = std::lower_bound(entries_.begin(), entries_.end(), frame,
                                   [](const KeyframeEntry& e, FrameId f) { return e.frame < f; });
  if (it == entries_.end() || it->frame != frame) return std::nullopt;
  return static_cast<size_t>(it - entries_.begin());
}

void RenameLandmarkIds(const std::unordered_map<LandmarkId, LandmarkId>& new_id,
                       std::vector<LandmarkId>* ids) {
  for (LandmarkId& id : *ids) {
    const auto it = new_id.find(id);
    if (it != new_id.end()) id = it->second;
  }
}

bool KeyframeDatabase::RenameLandmarks(FrameId frame,
                                       const std::unordered_map<LandmarkId, LandmarkId>& new_id) {
  const std::optional<size_t> i = IndexOf(frame);
  if (!i) return false;
  RenameLandmarkIds(new_id, &entries_[*i].landmark);
  return true;
}

}  // namespace dala
