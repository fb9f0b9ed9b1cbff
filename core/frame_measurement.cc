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

}  // namespace dala
