#ifndef DALA_CORE_IO_TUM_DATASET_H_
#define DALA_CORE_IO_TUM_DATASET_H_

// TUM RGB-D sequences (monocular: only the colour images are read, as grayscale):
//   rgb.txt            "t filename" per image, t in seconds, '#' comments
//   rgb/<t>.png        the images (640x480)
//   groundtruth.txt    optional, TUM format "t tx ty tz qx qy qz qw": the pose of the colour
//                      camera's optical centre in the motion-capture world, T_w_c0 (100 Hz),
//                      interpolated at the image times
// Intrinsics come from DatasetOptions::calibration_yaml or, without it, from the sequence name
// (a folder name containing freiburg1/2/3 or fr1/2/3), using the values TUM publishes for the
// colour camera (k1 k2 p1 p2 k3 in OpenCV order):
//   freiburg1: fx 517.3 fy 516.5 cx 318.6 cy 255.3  d 0.2624 -0.9531 -0.0054 0.0026 1.1633
//   freiburg2: fx 520.9 fy 521.0 cx 325.1 cy 249.7  d 0.2312 -0.7849 -0.0033 -0.0001 0.9172
//   freiburg3: fx 535.4 fy 539.2 cx 320.1 cy 247.6  d 0 (images already undistorted)
// Images with distortion are undistorted on reading (the rig is the undistorted camera).

#include <optional>
#include <string>

#include "core/camera.h"
#include "core/io/dataset.h"
#include "core/io/image_sequence.h"

namespace dala {

// The published colour-camera intrinsics for a sequence name, or nullopt when the name names no
// freiburg camera.
std::optional<PinholeCamera> TumIntrinsicsForSequence(const std::string& name);

// Throws dala::Error on a malformed folder or an unknown camera without a calibration YAML.
ImageSequence ReadTumSequence(const std::string& folder, const DatasetOptions& options);

}  // namespace dala

#endif  // DALA_CORE_IO_TUM_DATASET_H_
