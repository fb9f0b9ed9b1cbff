#ifndef DALA_CORE_IO_CALIBRATION_YAML_H_
#define DALA_CORE_IO_CALIBRATION_YAML_H_

// The calibration override file (DatasetOptions::calibration_yaml), a cv::FileStorage YAML map:
//
//   %YAML:1.0
//   fx: 707.0912        # required: focal lengths, principal point (pixels), image size
//   fy: 707.0912
//   cx: 601.8873
//   cy: 183.1104
//   width: 1226
//   height: 370
//   baseline: 0.537     # optional, metres; 0 or absent for a monocular camera
//   k1: 0.0             # optional radial-tangential distortion (OpenCV order k1 k2 p1 p2 k3);
//   k2: 0.0             # only for monocular images, which are then undistorted on reading
//
// Unknown keys are an error (a misspelt "basline" must not silently give a mono rig).

#include <string>

#include "core/camera.h"

namespace dala {

// Throws dala::Error naming the file and key on a missing required key, an unknown key, a wrong
// type or an invalid camera (non-positive focal length or size, distortion with a baseline).
StereoRig ReadCalibrationYaml(const std::string& path);

}  // namespace dala

#endif  // DALA_CORE_IO_CALIBRATION_YAML_H_
