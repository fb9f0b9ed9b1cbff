#include "core/frame_measurement.h"

namespace dala {

const char* TrackingStatusName(TrackingStatus status) {
  switch (status) {
    case TrackingStatus::kInitializing: return "initializing";
    case TrackingStatus::kTracking: return "tracking";
    case TrackingStatus::kLost: return "lost";
  }
  return "?";
}

std::unordered_map<LandmarkId, LandmarkId> IdsBeforeLoop(const LoopDetection& loop) {
  std::unordered_map<LandmarkId, LandmarkId> before;
  for (const auto& [cur, old] : loop.relabelled) before[old] = cur;
  return before;
}

FrameMeasurement WithIdsBeforeLoop(const FrameMeasurement& m) {
  FrameMeasurement out = m;
  if (!m.loop) return out;
  const std::unordered_map<LandmarkId, LandmarkId> before = IdsBeforeLoop(*m.loop);
  for (FeatureObservation& o : out.observations) {
    const auto it = before.find(o.landmark);
    if (it != before.end()) o.landmark = it->second;
  }
  return out;
}

}  // namespace dala
