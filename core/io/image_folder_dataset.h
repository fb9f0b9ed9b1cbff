#ifndef DALA_CORE_IO_IMAGE_FOLDER_DATASET_H_
#define DALA_CORE_IO_IMAGE_FOLDER_DATASET_H_

// A plain folder of images (png, jpg, jpeg, bmp, tif, tiff, pgm, ppm; any case) with a
// calibration file (DatasetOptions::calibration_yaml, required, any format
// core/io/camera_calibration.h reads):
//   - order: by file name; when every name is a number (1.png, 2.png, 10.png; 1403636579.5.jpg)
//     by that number;
//   - times: DatasetOptions::fps (frame i at i / fps), else a times file (times_file, else the
//     folder's times.txt; seconds, one per image), else the file names: a name with a decimal
//     point is seconds (12.345.png), an integer of 16 digits or more nanoseconds (EuRoC's
//     1403636579763555584.png); otherwise dala::Error asking for --fps or a times file;
//   - stereo: DatasetOptions::right_folder, its images paired with the left ones by name, or by
//     order when the names differ (the counts must then be equal);
//   - ground truth: DatasetOptions::ground_truth (TUM by time, KITTI by image index).
// The images are undistorted (mono) or rectified (stereo) at open from the calibration.

#include <string>
#include <vector>

#include "core/io/dataset.h"
#include "core/io/image_sequence.h"

namespace dala {

// The image files directly in `folder`, in the order above (empty when none).
std::vector<std::string> ListImageFiles(const std::string& folder);

// Throws dala::Error naming the folder or file and the fix: no image, no calibration, no times,
// unpaired right images, a calibration of another image size.
ImageSequence ReadImageFolderSequence(const std::string& folder, const DatasetOptions& options);

}  // namespace dala

#endif  // DALA_CORE_IO_IMAGE_FOLDER_DATASET_H_
