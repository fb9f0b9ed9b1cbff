#include "core/frame_measurement.h"

#include <unordered_map>

namespace dala {

const char* TrackingStatusName(TrackingStatus status) {
  switch (status) {
    case TrackingStatus::kInitializing: return "initializing";
    case TrackingStatus::kTracking: return "tracking";
    case TrackingStatus::kLost: return "lost";
  }
  return "?";
}

FrameMeasurement WithIdsBeforeLoop(const FrameMeasurement& m) {
  FrameMeasurement out = m;
  if (!m.loop) return out;
  std::unordered_map<LandmarkId, LandmarkId> before;  // Old id -> the id before the loop.
  for (const auto& [cur, old] : m.loop->relabelled) before[old] = cur;
  for (FeatureObservation& o : out.observations) {
    const auto it = before.find(o.landmark);
    if (it != before.end()) o.landmark = it->second;
  }
  return out;
}

}  // namespace dala
