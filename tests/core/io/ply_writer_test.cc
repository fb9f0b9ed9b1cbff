#include "core/io/ply_writer.h"

#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/error.h"
#include "tests/test_util.h"

namespace dala {
namespace {

using testing::TempDir;

struct ParsedPly {
  std::vector<std::string> header;  // Lines between "ply" and "end_header" (exclusive).
  std::string body;                 // Bytes after "end_header\n".
};

ParsedPly ReadPly(const std::string& path) {
  std::ifstream is(path, std::ios::binary);
  std::stringstream ss;
  ss << is.rdbuf();
  const std::string all = ss.str();
  ParsedPly ply;
  size_t pos = 0;
  EXPECT_EQ(all.substr(0, 4), "ply\n");
  pos = 4;
  while (pos < all.size()) {
    const size_t eol = all.find('\n', pos);
    if (eol == std::string::npos) break;
    const std::string line = all.substr(pos, eol - pos);
    pos = eol + 1;
    if (line == "end_header") {
      ply.body = all.substr(pos);
      return ply;
    }
    ply.header.push_back(line);
  }
  ADD_FAILURE() << "no end_header in " << path;
  return ply;
}

template <typename T>
T Get(const std::string& body, size_t* offset) {
  T value;
  EXPECT_LE(*offset + sizeof(T), body.size());
  std::memcpy(&value, body.data() + *offset, sizeof(T));
  *offset += sizeof(T);
  return value;
}

TEST(PlyWriter, FloatPointsWithColoursAndIdsReadBack) {
  TempDir dir;
  const std::vector<Eigen::Vector3d> points = {{1.5, -2.25, 3.0}, {1e3, 0.1, -7.0}, {0, 0, 0}};
  const std::vector<cv::Vec3b> colors = {{255, 0, 10}, {1, 2, 3}, {128, 128, 128}};
  const std::vector<int64_t> ids = {7, 123456789, -1};
  WritePly(dir / "map.ply", points, &colors, &ids);
  const ParsedPly ply = ReadPly(dir / "map.ply");
  const std::vector<std::string> expected_header = {"format binary_little_endian 1.0",
                                                    "comment written by dala",
                                                    "element vertex 3",
                                                    "property float x",
                                                    "property float y",
                                                    "property float z",
                                                    "property uchar red",
                                                    "property uchar green",
                                                    "property uchar blue",
                                                    "property int landmark_id"};
  EXPECT_EQ(ply.header, expected_header);
  ASSERT_EQ(ply.body.size(), 3u * (12 + 3 + 4));
  size_t off = 0;
  for (size_t i = 0; i < points.size(); ++i) {
    for (int k = 0; k < 3; ++k) {
      EXPECT_EQ(Get<float>(ply.body, &off), static_cast<float>(points[i][k])) << i << "," << k;
    }
    for (int k = 0; k < 3; ++k) EXPECT_EQ(Get<uint8_t>(ply.body, &off), colors[i][k]);
    EXPECT_EQ(Get<int32_t>(ply.body, &off), ids[i]);
  }
  EXPECT_EQ(off, ply.body.size());
  // No temporary file left beside it.
  int files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir.path())) {
    (void)entry;
    ++files;
  }
  EXPECT_EQ(files, 1);
}

TEST(PlyWriter, DoublePointsOnly) {
  TempDir dir;
  const std::vector<Eigen::Vector3d> points = {{0.1, 0.2, 0.3}, {-1e6 + 1e-4, 2, 3}};
  PlyWriteOptions options;
  options.double_coordinates = true;
  options.comment = "kitti 06";
  WritePly(dir / "p.ply", points, nullptr, nullptr, options);
  const ParsedPly ply = ReadPly(dir / "p.ply");
  const std::vector<std::string> expected_header = {"format binary_little_endian 1.0",
                                                    "comment kitti 06",
                                                    "element vertex 2",
                                                    "property double x",
                                                    "property double y",
                                                    "property double z"};
  EXPECT_EQ(ply.header, expected_header);
  ASSERT_EQ(ply.body.size(), 2u * 24);
  size_t off = 0;
  for (const Eigen::Vector3d& p : points) {
    for (int k = 0; k < 3; ++k) EXPECT_EQ(Get<double>(ply.body, &off), p[k]);  // Bit exact.
  }
}

TEST(PlyWriter, EmptyCloudIsAValidFile) {
  TempDir dir;
  WritePly(dir / "e.ply", {});
  const ParsedPly ply = ReadPly(dir / "e.ply");
  ASSERT_GE(ply.header.size(), 3u);
  EXPECT_EQ(ply.header[2], "element vertex 0");
  EXPECT_TRUE(ply.body.empty());
}

TEST(PlyWriter, UnwritablePathThrows) {
  TempDir dir;
  EXPECT_THROW(WritePly(dir / "no/such/dir/m.ply", {{1, 2, 3}}), Error);
}

TEST(PlyWriterDeathTest, SizeMismatchDies) {
  TempDir dir;
  const std::vector<cv::Vec3b> colors(1);
  EXPECT_DEATH(WritePly(dir / "m.ply", {{1, 2, 3}, {4, 5, 6}}, &colors), "colours for 2 points");
}

}  // namespace
}  // namespace dala
