#ifndef DALA_CORE_SIM_DATASET_WRITER_H_
#define DALA_CORE_SIM_DATASET_WRITER_H_

// Writes a synthetic sequence as a KITTI-like folder (what `dala synth` produces):
//   image_0/%06d.png   left images, 8-bit grey
//   image_1/%06d.png   right images (absent for mono)
//   calib.txt          "P0: ..." .. "P3: ..." 3x4 row-major; P1 = P3 = K [I | (-b, 0, 0)]
//   times.txt          frame times in seconds, one per line
//   poses.txt          KITTI rows: row-major 3x4 T_w_c0 per frame
//   calibration/       the raw cameras (with the lens, SimOptions::lens) in each calibration
//                      format dala reads: opencv.yml, kalibr.yaml, ros_camera_info.yaml (left
//                      camera), dala.yaml (when it can hold them: no fisheye, no raw pair)
//   synth.yaml         cv::FileStorage marker: format "dala-synthetic", version 1, options
//   odometry.txt       (optional) TUM: integrated noisy odometry (NoisyOdometry)
//   points.ply         (optional) true 3D scene points in the world frame (ASCII PLY)

#include <functional>
#include <string>

#include "core/sim/synthetic_sequence.h"

namespace dala::sim {

struct SyntheticDatasetOutputs {
  bool points = false;    // Write points.ply.
  bool odometry = false;  // Write odometry.txt.
  // Called after every `progress_every` frames with (frames done, total); may be empty.
  std::function<void(size_t, size_t)> progress;
  size_t progress_every = 50;
};

// Throws dala::Error (naming the option or path) on invalid options or an unwritable folder.
void WriteSyntheticDataset(const SimOptions& options, const std::string& dir,
                           const SyntheticDatasetOutputs& outputs);
inline void WriteSyntheticDataset(const SimOptions& options, const std::string& dir,
                                  bool write_points) {
  SyntheticDatasetOutputs outputs;
  outputs.points = write_points;
  WriteSyntheticDataset(options, dir, outputs);
}

}  // namespace dala::sim

#endif  // DALA_CORE_SIM_DATASET_WRITER_H_
