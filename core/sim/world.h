#ifndef DALA_CORE_SIM_WORLD_H_
#define DALA_CORE_SIM_WORLD_H_

// The presets of the synthetic world: a scene and a closed-form camera path for each.
//
// World frame w: x east, y north, z up (metres); the ground of the street scenes is z = 0.
// Camera frame: x right, y down, z forward. Paths give T_w_c of the left camera at time t.

#include <memory>
#include <string>
#include <vector>

#include "core/geometry.h"
#include "core/sim/scene.h"
#include "core/trajectory.h"

namespace dala::sim {

// A smooth camera path in closed form (sums of sinusoids of t), defined for every t >= 0.
class CameraPath {
 public:
  virtual ~CameraPath() = default;
  virtual Pose T_w_c(double t_s) const = 0;
};

struct PresetInfo {
  std::string name;
  std::string summary;
  double duration_s;  // Duration of the default sequence (frames = duration * fps).
};

// All presets, in a fixed order.
const std::vector<PresetInfo>& Presets();
// nullptr if there is no preset of that name.
const PresetInfo* FindPreset(const std::string& name);

struct World {
  Scene scene;
  std::unique_ptr<CameraPath> path;
};

// Builds a preset's world; everything (geometry, textures, placement) follows from `seed`.
// texel_density_scale multiplies the texels per metre of every surface
// (SyntheticSequenceOptions::texel_density_scale). CHECK-fails on an unknown name (validate with
// FindPreset first).
World BuildWorld(const std::string& preset, uint64_t seed, int texture_size = 1024,
                 double texel_density_scale = 1.0);

// The street world along a recorded path already placed on the street (PlaceOnStreet,
// core/sim/recorded_path.h): buildings line both sides of the path's ground track, as in the
// rover_loop city; the camera follows the path (RecordedPath, times from 0).
World BuildWorldAlongPath(const std::vector<StampedPose>& placed_path, uint64_t seed,
                          int texture_size = 1024, double texel_density_scale = 1.0);

}  // namespace dala::sim

#endif  // DALA_CORE_SIM_WORLD_H_
