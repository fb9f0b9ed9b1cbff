// Side-by-side comparison of the dala matcher with OpenCV ORB and SIFT on image pairs related by a
// known homography (rotation sweep, scale sweep, perspective viewpoint change, noise).
// A match is correct when its reprojection error |H p_a - p_b| is under 3 px.
//
//   matching_comparison [--markdown]     (prints a table; docs/matching.md holds its output)
//
// Pairs are made from a procedural textured image (tests/frontend/test_images.h) and, when the
// shared data is present, from KITTI 06 frame 0 (a real image).

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <opencv2/features2d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <vector>

#include "frontend/harris.h"
#include "frontend/matcher.h"
#include "tests/frontend/test_images.h"

namespace {

using Clock = std::chrono::steady_clock;
double Ms(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

struct Score {
  int matches = 0, correct = 0;
  double ms = 0.0;
};

int CountCorrect(const std::vector<cv::Point2f>& pa, const std::vector<cv::Point2f>& pb,
                 const cv::Mat& H) {
  int correct = 0;
  for (size_t k = 0; k < pa.size(); ++k) {
    const Eigen::Vector2d q = dala::testing::ApplyH(H, Eigen::Vector2d(pa[k].x, pa[k].y));
    if ((q - Eigen::Vector2d(pb[k].x, pb[k].y)).norm() < 3.0) ++correct;
  }
  return correct;
}

Score RunDala(const cv::Mat& a, const cv::Mat& b, const cv::Mat& H, bool homography_check) {
  const auto t0 = Clock::now();
  dala::HarrisOptions ho;
  const dala::DetectedImage da = dala::DetectHarris(a, ho);
  const dala::DetectedImage db = dala::DetectHarris(b, ho);
  dala::MatcherOptions mo;
  if (homography_check) mo.geometric_check = dala::GeometricCheck::kHomography;
  const std::vector<dala::Match> m = dala::MatchPoints(da, db, mo);
  Score s;
  s.ms = Ms(t0);
  std::vector<cv::Point2f> pa, pb;
  for (const auto& x : m) {
    pa.emplace_back(da.points[x.i].uv.x(), da.points[x.i].uv.y());
    pb.emplace_back(db.points[x.j].uv.x(), db.points[x.j].uv.y());
  }
  s.matches = static_cast<int>(m.size());
  s.correct = CountCorrect(pa, pb, H);
  return s;
}

Score RunOpenCv(const cv::Ptr<cv::Feature2D>& f, int norm, const cv::Mat& a, const cv::Mat& b,
                const cv::Mat& H) {
  const auto t0 = Clock::now();
  std::vector<cv::KeyPoint> ka, kb;
  cv::Mat da, db;
  f->detectAndCompute(a, cv::noArray(), ka, da);
  f->detectAndCompute(b, cv::noArray(), kb, db);
  std::vector<cv::Point2f> pa, pb;
  if (!da.empty() && !db.empty()) {
    cv::BFMatcher bf(norm);
    std::vector<std::vector<cv::DMatch>> knn;
    bf.knnMatch(da, db, knn, 2);
    for (const auto& k : knn) {
      if (k.size() == 2 && k[0].distance < 0.8f * k[1].distance) {
        pa.push_back(ka[k[0].queryIdx].pt);
        pb.push_back(kb[k[0].trainIdx].pt);
      }
    }
  }
  Score s;
  s.ms = Ms(t0);
  s.matches = static_cast<int>(pa.size());
  s.correct = CountCorrect(pa, pb, H);
  return s;
}

struct Pair {
  std::string name;
  cv::Mat a, b, H;
};

std::vector<Pair> MakePairs() {
  using dala::testing::SimilarityAboutCentre;
  using dala::testing::Warp;
  std::vector<std::pair<std::string, cv::Mat>> bases;
  bases.emplace_back("synth", dala::testing::MakeTexturedImage(640, 480, 7));
  const std::string kitti =
      std::string(DALA_SHARED_DATA_DIR) + "/kitti06_0000-0050/image_0/000000.png";
  if (std::filesystem::exists(kitti)) {
    cv::Mat k = cv::imread(kitti, cv::IMREAD_GRAYSCALE);
    if (!k.empty()) bases.emplace_back("kitti", k);
  } else {
    std::fprintf(stderr, "note: %s absent, KITTI pairs skipped\n", kitti.c_str());
  }
  const double deg = M_PI / 180.0;
  std::vector<Pair> pairs;
  for (const auto& [base_name, img] : bases) {
    for (double angle : {0.0, 30.0, 60.0, 90.0, 135.0, 180.0}) {
      cv::Mat H = SimilarityAboutCentre(img.size(), angle * deg, 1.0);
      pairs.push_back(
          {base_name + " rot " + std::to_string(static_cast<int>(angle)), img, Warp(img, H), H});
    }
    for (double scale : {1.25, 1.5, 2.0}) {
      cv::Mat H = SimilarityAboutCentre(img.size(), 0.0, scale);
      char name[64];
      std::snprintf(name, sizeof(name), "%s scale %.2f", base_name.c_str(), scale);
      pairs.push_back({name, img, Warp(img, H), H});
    }
    {
      cv::Mat H = SimilarityAboutCentre(img.size(), 40 * deg, 1.5);
      pairs.push_back({base_name + " rot 40 + scale 1.5", img, Warp(img, H), H});
    }
    {
      cv::Mat H = SimilarityAboutCentre(img.size(), 10 * deg, 1.0, 4e-4, 2e-4);
      pairs.push_back({base_name + " perspective", img, Warp(img, H), H});
    }
    {
      cv::Mat H = SimilarityAboutCentre(img.size(), 20 * deg, 1.2);
      cv::Mat b = Warp(img, H), noise(b.size(), CV_32F), f;
      cv::RNG rng(3);
      rng.fill(noise, cv::RNG::NORMAL, 0.0, 8.0);
      b.convertTo(f, CV_32F);
      f += noise;
      f.convertTo(b, CV_8U);
      pairs.push_back({base_name + " rot 20 scale 1.2 noise 8", img, b, H});
    }
  }
  return pairs;
}

}  // namespace

int main(int argc, char** argv) {
  const bool markdown = argc > 1 && std::string(argv[1]) == "--markdown";
  const std::vector<Pair> pairs = MakePairs();
  auto cell = [](const Score& s) {
    char buf[64];
    std::snprintf(buf, sizeof(buf), "%5.1f%% %4d %5.0f",
                  s.matches > 0 ? 100.0 * s.correct / s.matches : 0.0, s.correct, s.ms);
    return std::string(buf);
  };
  if (markdown) {
    std::printf(
        "| pair | dala (no check) | dala + homography | ORB 2000 + ratio | SIFT + ratio |\n");
    std::printf("|---|---|---|---|---|\n");
  } else {
    std::printf("%-28s | %-18s | %-18s | %-18s | %-18s\n", "pair (precision correct ms)", "dala",
                "dala+H", "ORB", "SIFT");
  }
  auto orb = cv::ORB::create(2000);
  auto sift = cv::SIFT::create();
  Score total[4];
  for (const Pair& p : pairs) {
    const Score s[4] = {RunDala(p.a, p.b, p.H, false), RunDala(p.a, p.b, p.H, true),
                        RunOpenCv(orb, cv::NORM_HAMMING, p.a, p.b, p.H),
                        RunOpenCv(sift, cv::NORM_L2, p.a, p.b, p.H)};
    for (int k = 0; k < 4; ++k) {
      total[k].matches += s[k].matches;
      total[k].correct += s[k].correct;
      total[k].ms += s[k].ms;
    }
    if (markdown) {
      std::printf("| %s | %s | %s | %s | %s |\n", p.name.c_str(), cell(s[0]).c_str(),
                  cell(s[1]).c_str(), cell(s[2]).c_str(), cell(s[3]).c_str());
    } else {
      std::printf("%-28s | %s | %s | %s | %s\n", p.name.c_str(), cell(s[0]).c_str(),
                  cell(s[1]).c_str(), cell(s[2]).c_str(), cell(s[3]).c_str());
    }
  }
  for (auto& t : total) t.ms /= static_cast<double>(pairs.size());
  if (markdown) {
    std::printf("| **all pairs** (mean ms) | %s | %s | %s | %s |\n", cell(total[0]).c_str(),
                cell(total[1]).c_str(), cell(total[2]).c_str(), cell(total[3]).c_str());
  } else {
    std::printf("%-28s | %s | %s | %s | %s\n", "ALL (mean ms)", cell(total[0]).c_str(),
                cell(total[1]).c_str(), cell(total[2]).c_str(), cell(total[3]).c_str());
  }
  return 0;
}
