#include "core/io/ply_writer.h"

#include <glog/logging.h>

#include <cstring>
#include <limits>

#include "core/io/atomic_file.h"

namespace dala {
namespace {

static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__,
              "WritePly writes the host's byte order as binary_little_endian");

template <typename T>
void Put(char*& out, T value) {
  std::memcpy(out, &value, sizeof(T));
  out += sizeof(T);
}

}  // namespace

void WritePly(const std::string& path, const std::vector<Eigen::Vector3d>& points,
              const std::vector<cv::Vec3b>* colors, const std::vector<int64_t>* ids,
              const PlyWriteOptions& options) {
  CHECK(colors == nullptr || colors->size() == points.size())
      << "WritePly: " << colors->size() << " colours for " << points.size() << " points";
  CHECK(ids == nullptr || ids->size() == points.size())
      << "WritePly: " << ids->size() << " ids for " << points.size() << " points";
  CHECK(options.comment.find('\n') == std::string::npos) << "WritePly: comment has a newline";
  const char* coord_type = options.double_coordinates ? "double" : "float";
  const size_t coord_size = options.double_coordinates ? sizeof(double) : sizeof(float);
  const size_t vertex_size = 3 * coord_size + (colors ? 3 : 0) + (ids ? sizeof(int32_t) : 0);

  std::vector<char> body(vertex_size * points.size());
  char* out = body.data();
  for (size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector3d& p = points[i];
    for (int k = 0; k < 3; ++k) {
      if (options.double_coordinates) {
        Put(out, p[k]);
      } else {
        Put(out, static_cast<float>(p[k]));
      }
    }
    if (colors) {
      for (int k = 0; k < 3; ++k) Put(out, (*colors)[i][k]);
    }
    if (ids) {
      const int64_t id = (*ids)[i];
      CHECK(id >= std::numeric_limits<int32_t>::min() && id <= std::numeric_limits<int32_t>::max())
          << "WritePly: landmark id " << id << " does not fit the PLY int property";
      Put(out, static_cast<int32_t>(id));
    }
  }
  CHECK(out == body.data() + body.size());

  WriteFileAtomically(path, [&](std::ostream& os) {
    os << "ply\nformat binary_little_endian 1.0\n";
    if (!options.comment.empty()) os << "comment " << options.comment << "\n";
    os << "element vertex " << points.size() << "\n";
    for (const char* axis : {"x", "y", "z"}) os << "property " << coord_type << " " << axis << "\n";
    if (colors) os << "property uchar red\nproperty uchar green\nproperty uchar blue\n";
    if (ids) os << "property int landmark_id\n";
    os << "end_header\n";
    os.write(body.data(), static_cast<std::streamsize>(body.size()));
  });
}

}  // namespace dala
