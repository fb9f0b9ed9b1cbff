#ifndef DALA_CORE_IO_MAP_FILE_H_
#define DALA_CORE_IO_MAP_FILE_H_

// The saved map of a SLAM run (System::SaveMap / LoadMap): keyframes with their poses and interest
// points (landmark id, position, orientation, scale and the matcher's patch descriptor), and the
// landmarks in the world frame. It holds what place recognition and relocalisation need.
//
// Binary format, version 3 (little-endian, IEEE floats; docs/api.md gives the same table):
//   char[8]  magic "DALAMAP\0"
//   uint32   version (3)
//   uint32   descriptor_size D (samples per descriptor; 0 when the map has none)
//   uint64   keyframe count, then per keyframe:
//              int64 frame id, int64 t_ns, float64[7] T_w_c as (qx qy qz qw tx ty tz),
//              uint64 point count, then per point:
//                int64 landmark id (-1: none), float64[2] uv (left image pixels),
//                float32 orientation (rad), float32 scale, float32[2] the Harris matrix's
//                eigenvalues (largest first; the matcher compares their ratio),
//                int8[D] descriptor (the patch at 8 bits, core/quantized_descriptors.h)
//   uint64   landmark count, then per landmark: int64 id, float64[3] p_w, int32 observations
//   uint32   metric: 1 when the map's unit is the metre (stereo), 0 when it is arbitrary (one
//            camera: the unit of its two-view initialisation)
//   uint32   thumbnail width W, uint32 thumbnail height H (0 0: no thumbnails), then per
//            keyframe, in the order above: float32[W*H] thumbnail (place recognition's global
//            descriptor, row-major), what ranks the keyframes when a run relocalises in the map
//   uint64   FNV-1a 64 hash of every preceding byte (detects truncation and corruption)
// A reader accepts exactly the versions it knows and says which ones when it meets another:
// version 2 (the same with float32[D] descriptors) is read and its descriptors quantised;
// version 1, before the metric flag and the thumbnails, is refused (save the map again).

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/geometry.h"
#include "core/types.h"

namespace dala {

struct MapFileVersion {
  static constexpr uint32_t kCurrent = 3;
  static constexpr uint32_t kFloatDescriptors = 2;  // Read, never written.
};
// What the reader accepts (and the writer refuses beyond): samples per descriptor, thumbnail side.
constexpr uint32_t kMaxDescriptorSize = 4096;
constexpr uint32_t kMaxThumbnailSide = 1024;

struct SavedKeyframePoint {
  LandmarkId landmark;  // Invalid when the point belongs to no landmark.
  Eigen::Vector2d uv = Eigen::Vector2d::Zero();
  float orientation = 0.f;
  float scale = 1.f;
  float lambda1 = 0.f;  // The Harris matrix's eigenvalues (frontend/harris.h).
  float lambda2 = 0.f;
  // descriptor_size samples (or empty when the map has none): the matcher's patch at 8 bits
  // (core/quantized_descriptors.h; ExpandDescriptor gives the floats back).
  std::vector<int8_t> descriptor;
};

struct SavedKeyframe {
  FrameId frame;
  int64_t t_ns = 0;
  Pose T_w_c = Pose::Identity();
  std::vector<SavedKeyframePoint> points;
  // The keyframe image's thumbnail (thumbnail_width x thumbnail_height of the map, row-major),
  // empty when the map has none.
  std::vector<float> thumbnail;
};

struct SavedLandmark {
  LandmarkId id;
  Eigen::Vector3d p_w = Eigen::Vector3d::Zero();
  int observations = 0;
};

struct SavedMap {
  int descriptor_size = 0;
  bool metric = true;  // false: one camera's arbitrary unit.
  int thumbnail_width = 0;  // 0 0: no thumbnails.
  int thumbnail_height = 0;
  std::vector<SavedKeyframe> keyframes;
  std::vector<SavedLandmark> landmarks;
};

// Writes atomically (a reader never sees half a file). Throws dala::Error when the file cannot
// be written, a point's descriptor does not have descriptor_size floats or a keyframe's
// thumbnail not thumbnail_width x thumbnail_height.
void WriteMapFile(const std::string& path, const SavedMap& map);
// The same with the keyframes beside the map (whose keyframes must be empty): for a caller that
// holds them elsewhere and should not copy them.
void WriteMapFile(const std::string& path, const SavedMap& map,
                  const std::vector<SavedKeyframe>& keyframes);

// Throws dala::Error naming the file and what is wrong: not a dala map, a version this build
// does not read, truncated or corrupted (hash mismatch), or counts that do not fit the file.
SavedMap ReadMapFile(const std::string& path);

}  // namespace dala

#endif  // DALA_CORE_IO_MAP_FILE_H_
