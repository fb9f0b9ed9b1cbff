#ifndef DALA_TESTS_FRONTEND_TEST_IMAGES_H_
#define DALA_TESTS_FRONTEND_TEST_IMAGES_H_

// Deterministic procedural test images and known-homography pairs for the frontend tests and
// benchmarks: layered random polygons, ellipses and strokes of varied grey at several scales,
// slightly blurred, with additive noise. Rich in corners of many angles, not a checkerboard,
// not noise.

#include <Eigen/Core>
#include <cmath>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <random>

namespace dala::testing {

inline cv::Mat MakeTexturedImage(int width, int height, uint32_t seed, double noise_sigma = 2.0) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  cv::Mat img(height, width, CV_8UC1, cv::Scalar(128));
  const double diag = std::hypot(width, height);
  // Coarse to fine layers: few large shapes, then many small ones.
  const double sizes[] = {0.25, 0.12, 0.06, 0.03};
  const int counts[] = {12, 40, 140, 400};
  for (int layer = 0; layer < 4; ++layer) {
    const int n = counts[layer] * width * height / (640 * 480);
    for (int k = 0; k < n; ++k) {
      const double size = sizes[layer] * diag * (0.5 + u(rng));
      const cv::Point2d c(u(rng) * width, u(rng) * height);
      const cv::Scalar grey(20 + 215 * u(rng));
      const double kind = u(rng);
      if (kind < 0.5) {  // Random polygon (3..6 vertices around c).
        const int nv = 3 + static_cast<int>(u(rng) * 4);
        std::vector<cv::Point> poly;
        double angle = u(rng) * 2 * M_PI;
        for (int v = 0; v < nv; ++v) {
          angle += (0.5 + u(rng)) * 2 * M_PI / nv;
          const double r = size * (0.3 + 0.7 * u(rng));
          poly.emplace_back(cvRound(c.x + r * std::cos(angle)), cvRound(c.y + r * std::sin(angle)));
        }
        cv::fillPoly(img, std::vector<std::vector<cv::Point>>{poly}, grey, cv::LINE_AA);
      } else if (kind < 0.8) {  // Ellipse.
        cv::ellipse(
            img, cv::Point(cvRound(c.x), cvRound(c.y)),
            cv::Size(cvRound(size * (0.2 + 0.5 * u(rng))), cvRound(size * (0.2 + 0.5 * u(rng)))),
            u(rng) * 180.0, 0, 360, grey, -1, cv::LINE_AA);
      } else {  // Stroke.
        const double a = u(rng) * 2 * M_PI;
        const cv::Point p0(cvRound(c.x), cvRound(c.y));
        const cv::Point p1(cvRound(c.x + size * std::cos(a)), cvRound(c.y + size * std::sin(a)));
        cv::line(img, p0, p1, grey, 1 + static_cast<int>(u(rng) * size * 0.1), cv::LINE_AA);
      }
    }
  }
  cv::GaussianBlur(img, img, cv::Size(0, 0), 0.8);
  if (noise_sigma > 0.0) {
    cv::Mat noise(img.size(), CV_32F);
    cv::RNG cv_rng(seed * 7919u + 1u);
    cv_rng.fill(noise, cv::RNG::NORMAL, 0.0, noise_sigma);
    cv::Mat f;
    img.convertTo(f, CV_32F);
    f += noise;
    f.convertTo(img, CV_8UC1);
  }
  return img;
}

// Homography rotating by `angle_rad` and scaling by `scale` about the image centre, followed by a
// perspective tilt (h20, h21 in 1/px) about the centre.
inline cv::Mat SimilarityAboutCentre(cv::Size size, double angle_rad, double scale,
                                     double h20 = 0.0, double h21 = 0.0) {
  const double cx = 0.5 * (size.width - 1), cy = 0.5 * (size.height - 1);
  cv::Mat T = (cv::Mat_<double>(3, 3) << 1, 0, cx, 0, 1, cy, 0, 0, 1);
  cv::Mat Ti = (cv::Mat_<double>(3, 3) << 1, 0, -cx, 0, 1, -cy, 0, 0, 1);
  const double c = std::cos(angle_rad) * scale, s = std::sin(angle_rad) * scale;
  cv::Mat S = (cv::Mat_<double>(3, 3) << c, -s, 0, s, c, 0, 0, 0, 1);
  cv::Mat P = (cv::Mat_<double>(3, 3) << 1, 0, 0, 0, 1, 0, h20, h21, 1);
  cv::Mat H = T * P * S * Ti;
  return H / H.at<double>(2, 2);
}

inline cv::Mat Warp(const cv::Mat& img, const cv::Mat& H) {
  cv::Mat out;
  cv::warpPerspective(img, out, H, img.size(), cv::INTER_LINEAR, cv::BORDER_CONSTANT,
                      cv::Scalar(0));
  return out;
}

inline Eigen::Vector2d ApplyH(const cv::Mat& H, const Eigen::Vector2d& p) {
  const double x = H.at<double>(0, 0) * p.x() + H.at<double>(0, 1) * p.y() + H.at<double>(0, 2);
  const double y = H.at<double>(1, 0) * p.x() + H.at<double>(1, 1) * p.y() + H.at<double>(1, 2);
  const double w = H.at<double>(2, 0) * p.x() + H.at<double>(2, 1) * p.y() + H.at<double>(2, 2);
  return Eigen::Vector2d(x / w, y / w);
}

}  // namespace dala::testing

#endif  // DALA_TESTS_FRONTEND_TEST_IMAGES_H_
