#ifndef DALA_TESTS_FUZZ_FIXTURES_H_
#define DALA_TESTS_FUZZ_FIXTURES_H_

// Small valid dataset folders in the scratch directory; a target replaces one file with the
// fuzz input, so the reader gets past the other checks and reaches the code under test.

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>

#include "tests/fuzz/fuzz_util.h"

namespace dala::fuzz {

inline void WriteTinyPng(const std::string& path) {
  std::filesystem::create_directories(std::filesystem::path(path).parent_path());
  cv::Mat image(12, 16, CV_8UC1);
  cv::randu(image, 0, 255);
  CHECK(cv::imwrite(path, image)) << path;
}

// A stereo KITTI folder with two 16x12 frames; returns its path.
inline std::string KittiFolder() {
  static const std::string folder = [] {
    const std::string f = ScratchDir::Path() + "/kitti";
    for (const char* name : {"image_0/000000.png", "image_0/000001.png", "image_1/000000.png",
                             "image_1/000001.png"}) {
      WriteTinyPng(f + "/" + name);
    }
    return f;
  }();
  // Restore the valid files every time: the previous input may have replaced any of them.
  WriteScratchFile("kitti/calib.txt",
                   "P0: 10 0 8 0 0 10 6 0 0 0 1 0\nP1: 10 0 8 -5 0 10 6 0 0 0 1 0\n");
  WriteScratchFile("kitti/times.txt", "0.0\n0.1\n");
  std::filesystem::remove(folder + "/poses.txt");
  return folder;
}

// A monocular EuRoC folder (mav0/cam0) with one 16x12 image at t = 1000 ns.
inline std::string EurocFolder() {
  static const std::string folder = [] {
    const std::string f = ScratchDir::Path() + "/euroc";
    WriteTinyPng(f + "/mav0/cam0/data/1000.png");
    WriteTinyPng(f + "/mav0/cam0/data/2000.png");
    WriteScratchFile("euroc/mav0/cam0/sensor.yaml",
                     "%YAML:1.0\n"
                     "T_BS:\n  rows: 4\n  cols: 4\n"
                     "  data: [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]\n"
                     "resolution: [16, 12]\ncamera_model: pinhole\n"
                     "intrinsics: [10, 10, 8, 6]\n"
                     "distortion_model: radial-tangential\n"
                     "distortion_coefficients: [0.01, 0, 0, 0]\n");
    return f;
  }();
  WriteScratchFile("euroc/mav0/cam0/data.csv", "#timestamp [ns],filename\n1000,1000.png\n");
  return folder;
}

}  // namespace dala::fuzz

#endif  // DALA_TESTS_FUZZ_FIXTURES_H_
