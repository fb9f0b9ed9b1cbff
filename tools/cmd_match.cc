// `dala match A B`: detect precise Harris points in two images, match them with the robust group
// matcher, draw the matches, and score them against a ground-truth homography when given.
#include <gflags/gflags.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "core/error.h"
#include "core/yaml_single_document.h"
#include "frontend/harris.h"
#include "frontend/matcher.h"
#include "tools/command.h"

DECLARE_string(out);  // tools/common_flags.cc
DECLARE_bool(json);  // tools/common_flags.cc
DEFINE_string(homography, "",
              "match: ground-truth 3x3 homography mapping A to B (OpenCV XML/YAML file with a "
              "3x3 matrix node, or a text file of 9 numbers, row-major)");
DEFINE_string(match_check, "none",
              "match: geometric check after matching: none|homography|fundamental");
DEFINE_int32(match_levels, 4, "match: pyramid levels of the detector (1 = no pyramid)");
DEFINE_double(match_correct_px, 3.0,
              "match: a match is correct when |H a - b| is under this many pixels");

namespace dala {
namespace {

cv::Mat ReadGray(const std::string& path) {
  if (!std::filesystem::exists(path)) {
    throw Error() << path << ": no such image file";
  }
  cv::Mat img = cv::imread(path, cv::IMREAD_GRAYSCALE);
  if (img.empty()) throw Error() << path << ": cannot decode the image (PNG, JPG, PGM, ...)";
  return img;
}

// A 3x3 homography from a text file of 9 numbers or an OpenCV XML/YAML file.
cv::Mat ReadHomography(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw Error() << path << ": cannot open the homography file";
  std::stringstream buffer;
  buffer << in.rdbuf();
  const std::string text = buffer.str();
  {
    std::istringstream is(text);
    std::vector<double> v;
    std::string token;
    bool all_numbers = true;
    while (is >> token) {
      char* end = nullptr;
      const double x = std::strtod(token.c_str(), &end);
      if (end == token.c_str() || *end != '\0') {
        all_numbers = false;
        break;
      }
      v.push_back(x);
    }
    if (all_numbers) {
      if (v.size() != 9) {
        throw Error() << path << ": expected 9 numbers (a row-major 3x3 homography), got "
                      << v.size();
      }
      cv::Mat H(3, 3, CV_64F);
      for (int k = 0; k < 9; ++k) H.at<double>(k / 3, k % 3) = v[k];
      return H;
    }
  }
  // OpenCV's YAML parser can hang on a second document (core/yaml_single_document.h).
  if (text.rfind("%YAML", 0) == 0) CheckSingleYamlDocument(text, path);
  cv::Mat H;
  try {
    cv::FileStorage fs(text, cv::FileStorage::READ | cv::FileStorage::MEMORY);
    if (fs.isOpened()) {
      for (const auto& node : fs.root()) {
        cv::Mat m;
        if (node.isMap() || node.isSeq()) {
          try {
            node >> m;
          } catch (const cv::Exception&) {
            continue;
          }
        }
        if (m.rows == 3 && m.cols == 3) {
          m.convertTo(H, CV_64F);
          break;
        }
      }
    }
  } catch (const cv::Exception&) {
    // Falls through to the error below.
  }
  if (H.empty()) {
    throw Error() << path
                  << ": no 3x3 matrix found; give 9 numbers (row-major) or an OpenCV XML/YAML "
                     "file with a 3x3 matrix node (e.g. `H: !!opencv-matrix`)";
  }
  if (!cv::checkRange(H) || std::abs(cv::determinant(H)) < 1e-12) {
    throw Error() << path << ": the homography is singular or not finite";
  }
  return H;
}

GeometricCheck ParseCheck(const std::string& s) {
  if (s == "none") return GeometricCheck::kNone;
  if (s == "homography") return GeometricCheck::kHomography;
  if (s == "fundamental") return GeometricCheck::kFundamental;
  throw Error() << "--match_check=" << s << ": expected none, homography or fundamental";
}

int RunMatch(const std::vector<std::string>& args) {
  if (args.size() != 2) {
    throw Error() << "expected two images, got " << args.size()
                  << " arguments; usage: dala match A B [--homography H] [--out m.png] [--json]";
  }
  const cv::Mat a = ReadGray(args[0]);
  const cv::Mat b = ReadGray(args[1]);
  cv::Mat H;
  if (!FLAGS_homography.empty()) H = ReadHomography(FLAGS_homography);
  HarrisOptions harris;
  harris.num_levels = FLAGS_match_levels;
  MatcherOptions options;
  options.geometric_check = ParseCheck(FLAGS_match_check);
  std::string why;
  if (!harris.IsValid(&why)) throw Error() << "--match_levels: " << why;

  const auto t0 = std::chrono::steady_clock::now();
  const DetectedImage da = DetectHarris(a, harris);
  const DetectedImage db = DetectHarris(b, harris);
  MatchStats stats;
  const std::vector<Match> matches = MatchPoints(da, db, options, nullptr, &stats);
  const double ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();

  std::vector<bool> correct(matches.size(), true);
  int num_correct = 0;
  if (!H.empty()) {
    for (size_t k = 0; k < matches.size(); ++k) {
      const Eigen::Vector2d& p = da.points[matches[k].i].uv;
      cv::Mat x = H * (cv::Mat_<double>(3, 1) << p.x(), p.y(), 1.0);
      const Eigen::Vector2d q(x.at<double>(0) / x.at<double>(2), x.at<double>(1) / x.at<double>(2));
      correct[k] = (q - db.points[matches[k].j].uv).norm() < FLAGS_match_correct_px;
      num_correct += correct[k] ? 1 : 0;
    }
  }

  if (!FLAGS_out.empty()) {
    std::vector<cv::KeyPoint> ka, kb;
    for (const auto& p : da.points) ka.emplace_back(p.uv.x(), p.uv.y(), 7.f * p.scale);
    for (const auto& p : db.points) kb.emplace_back(p.uv.x(), p.uv.y(), 7.f * p.scale);
    cv::Mat canvas;
    cv::drawMatches(a, ka, b, kb, std::vector<cv::DMatch>(), canvas);
    for (size_t k = 0; k < matches.size(); ++k) {
      const cv::Point2f pa(ka[matches[k].i].pt);
      const cv::Point2f pb = kb[matches[k].j].pt + cv::Point2f(static_cast<float>(a.cols), 0.f);
      const cv::Scalar colour = correct[k] ? cv::Scalar(0, 200, 0) : cv::Scalar(0, 0, 255);
      cv::line(canvas, pa, pb, colour, 1, cv::LINE_AA);
      cv::circle(canvas, pa, 2, colour, -1, cv::LINE_AA);
      cv::circle(canvas, pb, 2, colour, -1, cv::LINE_AA);
    }
    bool written = false;
    try {
      written = cv::imwrite(FLAGS_out, canvas);
    } catch (const cv::Exception& e) {
      throw Error() << "--out=" << FLAGS_out << ": cannot write the image: " << e.what();
    }
    if (!written) {
      throw Error() << "--out=" << FLAGS_out
                    << ": cannot write the image (is the folder there, the extension known?)";
    }
  }

  if (FLAGS_json) {
    nlohmann::json j;
    j["matches"] = matches.size();
    j["points_a"] = da.points.size();
    j["points_b"] = db.points.size();
    j["ms"] = ms;
    if (!H.empty()) {
      j["correct"] = num_correct;
      j["precision"] = matches.empty() ? 0.0 : static_cast<double>(num_correct) / matches.size();
    } else {
      j["correct"] = nullptr;
      j["precision"] = nullptr;
    }
    std::cout << j.dump() << "\n";
  } else {
    std::cout << "points: " << da.points.size() << " in A, " << db.points.size() << " in B\n"
              << "matches: " << matches.size() << " (candidates " << stats.candidates
              << ", confirmed " << stats.confirmed << ", propagated " << stats.propagated << ")\n";
    if (!H.empty()) {
      std::cout << "correct: " << num_correct << " (|H a - b| < " << FLAGS_match_correct_px
                << " px)\nprecision: "
                << (matches.empty() ? 0.0 : 100.0 * num_correct / matches.size()) << " %\n";
    }
    std::cout << "time: " << ms << " ms (detection of both images + matching)\n";
  }
  return 0;
}

static CommandRegistrar registrar(
    {"match", "match interest points between two images (and score them against a homography)",
     "dala match A B [--homography H.txt|H.yml] [--out matches.png] [--json] "
     "[--match_check none|homography|fundamental]\n\n"
     "Detects precise Harris points in images A and B, matches them with the group-constrained\n"
     "matcher (any rotation, scale changes up to about 2), prints the number of matches and,\n"
     "with --homography (the 3x3 matrix mapping A pixels to B pixels), how many are correct\n"
     "and the precision. --out draws them side by side (green correct, red wrong).",
     &RunMatch, __FILE__});

}  // namespace
}  // namespace dala
