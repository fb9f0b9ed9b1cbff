#ifndef DALA_TESTS_CORE_IO_DATASET_FIXTURES_H_
#define DALA_TESTS_CORE_IO_DATASET_FIXTURES_H_

// Small dataset folders written by the tests (tiny random PNGs), for the readers' tests.

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>

#include "core/error.h"
#include "tests/test_util.h"  // ErrorOf

namespace dala::testing {

inline cv::Mat RandomImage(int width, int height, int seed) {
  cv::Mat image(height, width, CV_8UC1);
  cv::RNG rng(seed);
  rng.fill(image, cv::RNG::UNIFORM, 0, 256);
  return image;
}

inline void WriteText(const std::string& path, const std::string& text) {
  std::filesystem::create_directories(std::filesystem::path(path).parent_path());
  std::ofstream os(path);
  os << text;
}

inline std::string KittiName(int i) {
  char name[32];
  std::snprintf(name, sizeof(name), "%06d.png", i);
  return name;
}

struct KittiFixture {
  int frames = 4;
  int width = 64, height = 48;
  bool stereo = true;
  bool poses = true;
  double fx = 100, cx = 31.5, cy = 23.5, baseline = 0.5;
};

// Writes a KITTI-layout folder; frame i's left image is RandomImage(w, h, i), right 1000 + i.
// Ground-truth pose i translates by (0, 0, i) metres.
inline void WriteKittiFolder(const std::string& folder, const KittiFixture& f) {
  std::filesystem::create_directories(folder + "/image_0");
  if (f.stereo) std::filesystem::create_directories(folder + "/image_1");
  std::string times, poses;
  for (int i = 0; i < f.frames; ++i) {
    cv::imwrite(folder + "/image_0/" + KittiName(i), RandomImage(f.width, f.height, i));
    if (f.stereo) {
      cv::imwrite(folder + "/image_1/" + KittiName(i), RandomImage(f.width, f.height, 1000 + i));
    }
    times += std::to_string(0.1 * i) + "\n";
    poses += "1 0 0 0 0 1 0 0 0 0 1 " + std::to_string(i) + "\n";
  }
  WriteText(folder + "/times.txt", times);
  if (f.poses) WriteText(folder + "/poses.txt", poses);
  char calib[1024];
  std::snprintf(calib, sizeof(calib),
                "P0: %g 0 %g 0 0 %g %g 0 0 0 1 0\nP1: %g 0 %g %g 0 %g %g 0 0 0 1 0\n"
                "P2: %g 0 %g 0 0 %g %g 0 0 0 1 0\n",
                f.fx, f.cx, f.fx, f.cy, f.fx, f.cx, -f.fx * f.baseline, f.fx, f.cy, f.fx, f.cx,
                f.fx, f.cy);
  WriteText(folder + "/calib.txt", calib);
}

}  // namespace dala::testing

#endif  // DALA_TESTS_CORE_IO_DATASET_FIXTURES_H_
