#ifndef DALA_CORE_IO_KITTI_DATASET_H_
#define DALA_CORE_IO_KITTI_DATASET_H_

// KITTI odometry sequence folders (also the layout of the synthetic sequences):
//   image_0/000000.png ...   left grayscale images, rectified
//   image_1/000000.png ...   right images (absent: monocular)
//   calib.txt                "P0: 12 numbers" (row-major 3x4 projection), "P1: ..."
//   times.txt                one time in seconds per image
//   poses.txt                optional ground truth T_w_c0, 12 numbers per line; or, in the
//                            official layout dataset/sequences/NN/, ../../poses/NN.txt
// fx fy cx cy come from P0, the baseline b = -P1(0,3) / P1(0,0) (P1 = K [I | (-b, 0, 0)]).

#include <string>

#include "core/io/dataset.h"
#include "core/io/image_sequence.h"

namespace dala {

// Reads the folder into a sequence labelled `format` (kKitti or kSynthetic). Throws dala::Error
// on a malformed folder (see docs/datasets.md).
ImageSequence ReadKittiSequence(const std::string& folder, const DatasetOptions& options,
                                DatasetFormat format = DatasetFormat::kKitti);

// Parses "P<index>: 12 numbers" from a KITTI calib.txt; nullopt when the row is absent. Throws
// dala::Error naming file:line when the row has the wrong number of values.
std::optional<Eigen::Matrix<double, 3, 4>> ReadKittiProjection(const std::string& calib_path,
                                                               int index);

}  // namespace dala

#endif  // DALA_CORE_IO_KITTI_DATASET_H_
