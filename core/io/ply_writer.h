#ifndef DALA_CORE_IO_PLY_WRITER_H_
#define DALA_CORE_IO_PLY_WRITER_H_

// Writes a point cloud (the map) as a binary little-endian PLY file that MeshLab, CloudCompare
// and Open3D read. One vertex per point with, in this order:
//   x y z            float (default) or double, in the frame the caller gives (usually world)
//   red green blue   uchar, when colours are given
//   landmark_id      int (32-bit), when ids are given
// The file is written atomically (WriteFileAtomically): a failed write leaves no partial file.

#include <Eigen/Core>
#include <cstdint>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace dala {

struct PlyWriteOptions {
  // Store coordinates as double instead of float (float keeps ~0.1 mm at 1 km: enough for maps).
  bool double_coordinates = false;
  // Free text written as a "comment" header line (no newlines), e.g. the sequence name.
  std::string comment = "written by dala";
};

// `colors` (optional, one per point) are in R, G, B order: colors[i][0] is red (NOT OpenCV's BGR
// order; convert with cv::Vec3b(bgr[2], bgr[1], bgr[0])). `ids` (optional, one per point) must fit
// in 32 bits. Sizes must match (CHECK). Throws dala::Error when the file cannot be written.
void WritePly(const std::string& path, const std::vector<Eigen::Vector3d>& points,
              const std::vector<cv::Vec3b>* colors = nullptr,
              const std::vector<int64_t>* ids = nullptr, const PlyWriteOptions& options = {});

}  // namespace dala

#endif  // DALA_CORE_IO_PLY_WRITER_H_
