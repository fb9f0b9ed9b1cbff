#ifndef DALA_CORE_IO_BAG_DATASET_H_
#define DALA_CORE_IO_BAG_DATASET_H_

// A ROS 1 bag (`dala run FILE.bag --topic /cam0/image_raw [--right_topic /cam1/image_raw]`):
//   - images: sensor_msgs/Image (mono8, bgr8, rgb8, bgra8, rgba8) or sensor_msgs/CompressedImage
//     (png, jpeg) on DatasetOptions::topic (empty: the bag's only image topic); a stereo pair
//     adds right_topic, its images paired with the left ones by identical header stamps;
//   - times: the messages' header stamps (the bag's record time when a stamp is 0);
//   - calibration: DatasetOptions::calibration_yaml, else the sensor_msgs/CameraInfo of each
//     image topic's namespace (<ns>/camera_info) when the bag has it: one camera is undistorted,
//     a pair rectified with the CameraInfo's R and P (as ROS's stereo_image_proc does);
//   - ground truth: DatasetOptions::ground_truth (TUM by time, KITTI by frame index).
// Read through Debian's librosbag-dev and libsensor-msgs-dev when dala was built with them
// (CMake option DALA_WITH_ROSBAG, on when found); otherwise OpenBagDataset says how to get them.

#include <memory>
#include <string>

#include "core/io/dataset.h"

namespace dala {

// True when this build reads bags.
bool HaveBagSupport();

// Throws dala::Error naming the bag and the fix: no bag support in this build, an unreadable
// bag, a topic the bag lacks (listing the bag's topics), a bag without images, no calibration.
std::unique_ptr<Dataset> OpenBagDataset(const std::string& path, const DatasetOptions& options);

}  // namespace dala

#endif  // DALA_CORE_IO_BAG_DATASET_H_
