#include "core/sim/texture.h"

#include <glog/logging.h>

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "core/sim/random.h"

namespace dala::sim {
namespace {

bool IsPowerOfTwo(int n) { return n > 0 && (n & (n - 1)) == 0; }

// Gaussian blur of a tileable image with wrap-around borders (GaussianBlur has no BORDER_WRAP).
cv::Mat BlurWrap(const cv::Mat& img, double sigma) {
  const int pad = std::min(img.cols, static_cast<int>(std::ceil(3.5 * sigma)) + 2);
  cv::Mat padded;
  cv::copyMakeBorder(img, padded, pad, pad, pad, pad, cv::BORDER_WRAP);
  cv::GaussianBlur(padded, padded, cv::Size(0, 0), sigma);
  return padded(cv::Rect(pad, pad, img.cols, img.rows)).clone();
}

// pyrDown with wrap-around borders (the texture tiles), so the seams stay invisible.
cv::Mat PyrDownWrap(const cv::Mat& src) {
  constexpr int kPad = 4;
  cv::Mat padded, down;
  cv::copyMakeBorder(src, padded, kPad, kPad, kPad, kPad, cv::BORDER_WRAP);
  cv::pyrDown(padded, down);
  return down(cv::Rect(kPad / 2, kPad / 2, src.cols / 2, src.rows / 2)).clone();
}

using Rng = SimRng;

// Draws `draw(offset)` at the wrapped copies that overlap the image, so a shape (centre c,
// radius r) crossing a border reappears on the opposite side (a seamless tile).
template <typename Draw>
void DrawWrapped(int side, const cv::Point2d& c, double r, const Draw& draw) {
  const auto overlaps = [&](double x, int d) {
    return d == 0 || (d < 0 ? x + r + 2 >= side : x - r - 2 < 0);
  };
  for (int dy = -1; dy <= 1; ++dy) {
    if (!overlaps(c.y, dy)) continue;
    for (int dx = -1; dx <= 1; ++dx) {
      if (overlaps(c.x, dx)) draw(cv::Point(dx * side, dy * side));
    }
  }
}

// One random shape of radius ~r at a random place: a random polygon (3-7 vertices, star-like
// radii so it has both convex and concave corners), an ellipse, a rotated rectangle or a stroke.
void DrawRandomShape(Rng& rng, cv::Mat& img, double r, double grey_lo, double grey_hi,
                     bool allow_strokes) {
  const int side = img.cols;
  constexpr int kShift = 4;  // Sub-pixel vertex precision for cv drawing.
  constexpr double kScale = 1 << kShift;
  const cv::Point2d c(rng.Uniform(0, side), rng.Uniform(0, side));
  const cv::Scalar grey(rng.Uniform(grey_lo, grey_hi));
  const double kind = rng.Uniform();
  if (kind < 0.5) {
    const int n = rng.Int(3, 7);
    const double phase = rng.Uniform(0, 2 * M_PI);
    std::vector<cv::Point> pts(n);
    for (int k = 0; k < n; ++k) {
      const double a = phase + 2 * M_PI * (k + rng.Uniform(-0.3, 0.3)) / n;
      const double rr = r * rng.Uniform(0.35, 1.0);
      pts[k] = cv::Point(cvRound((c.x + rr * std::cos(a)) * kScale),
                         cvRound((c.y + rr * std::sin(a)) * kScale));
    }
    DrawWrapped(side, c, 2.0 * r, [&](cv::Point o) {
      std::vector<cv::Point> q(pts);
      for (auto& p : q) p += o * kScale;
      cv::fillPoly(img, std::vector<std::vector<cv::Point>>{q}, grey, cv::LINE_AA, kShift);
    });
  } else if (kind < 0.7) {
    const cv::Size axes(std::max(1, cvRound(r * rng.Uniform(0.4, 1.0))),
                        std::max(1, cvRound(r * rng.Uniform(0.2, 0.7))));
    const double angle = rng.Uniform(0, 180);
    DrawWrapped(side, c, 2.0 * r, [&](cv::Point o) {
      cv::ellipse(img, cv::Point(cvRound(c.x), cvRound(c.y)) + o, axes, angle, 0, 360, grey,
                  cv::FILLED, cv::LINE_AA);
    });
  } else if (kind < 0.88 || !allow_strokes) {
    const cv::RotatedRect rect(c, cv::Size2f(r * rng.Uniform(0.5, 2.0), r * rng.Uniform(0.3, 1.2)),
                               rng.Uniform(0, 180));
    cv::Point2f v[4];
    rect.points(v);
    DrawWrapped(side, c, 2.0 * r, [&](cv::Point o) {
      std::vector<cv::Point> q(4);
      for (int k = 0; k < 4; ++k) {
        q[k] = cv::Point(cvRound((v[k].x + o.x) * kScale), cvRound((v[k].y + o.y) * kScale));
      }
      cv::fillPoly(img, std::vector<std::vector<cv::Point>>{q}, grey, cv::LINE_AA, kShift);
    });
  } else {
    // A polyline stroke with a bend: gives L- and V-shaped corners.
    const int thickness = std::max(1, cvRound(r * rng.Uniform(0.08, 0.25)));
    const double a0 = rng.Uniform(0, 2 * M_PI), a1 = a0 + rng.Uniform(0.6, 2.5);
    const cv::Point p0(cvRound(c.x + r * std::cos(a0)), cvRound(c.y + r * std::sin(a0)));
    const cv::Point p1(cvRound(c.x), cvRound(c.y));
    const cv::Point p2(cvRound(c.x + r * std::cos(a1)), cvRound(c.y + r * std::sin(a1)));
    DrawWrapped(side, c, 2.0 * r, [&](cv::Point o) {
      cv::line(img, p0 + o, p1 + o, grey, thickness, cv::LINE_AA);
      cv::line(img, p1 + o, p2 + o, grey, thickness, cv::LINE_AA);
    });
  }
}

// A smooth tileable background: `count` large soft shapes blurred with sigma `sigma` (in
// 1024-texture texels). Drawn and blurred at 1/8 resolution, then enlarged: the same look at a
// fraction of the cost of a wide blur at full resolution.
cv::Mat SmoothBackground(Rng& rng, int side, double base, double lo, double hi, int count,
                         double sigma) {
  const int small_side = side / 8;
  const double s = small_side / 1024.0;
  cv::Mat small(small_side, small_side, CV_8UC1, cv::Scalar(base));
  for (int i = 0; i < count; ++i) DrawRandomShape(rng, small, 230 * s, lo, hi, false);
  small = BlurWrap(small, sigma * s);
  // Enlarge with wrap-around so the tile stays seamless.
  cv::Mat padded, big;
  cv::copyMakeBorder(small, padded, 1, 1, 1, 1, cv::BORDER_WRAP);
  cv::resize(padded, big, cv::Size((small_side + 2) * 8, (small_side + 2) * 8), 0, 0,
             cv::INTER_LINEAR);
  return big(cv::Rect(8, 8, side, side)).clone();
}

}  // namespace

Texture::Texture(const cv::Mat& base) {
  CHECK_EQ(base.rows, base.cols) << "texture must be square";
  CHECK(IsPowerOfTwo(base.cols) && base.cols >= 8) << "texture side must be a power of two >= 8";
  CHECK_EQ(base.channels(), 1);
  size_ = base.cols;
  cv::Mat level;
  base.convertTo(level, CV_32F);
  levels_.push_back(level);
  while (levels_.back().cols > 4) levels_.push_back(PyrDownWrap(levels_.back()));
}

float Texture::SampleLevel(int l, double x, double y) const {
  const cv::Mat& m = levels_[l];
  const int n = m.cols;
  const int mask = n - 1;
  const double scale = 1.0 / static_cast<double>(1 << l);
  const double xl = x * scale, yl = y * scale;
  // floor() by truncation toward zero, corrected for negative non-integers.
  int64_t ix = static_cast<int64_t>(xl), iy = static_cast<int64_t>(yl);
  ix -= static_cast<double>(ix) > xl;
  iy -= static_cast<double>(iy) > yl;
  const float ax = static_cast<float>(xl - static_cast<double>(ix));
  const float ay = static_cast<float>(yl - static_cast<double>(iy));
  const int x0 = static_cast<int>(ix & mask), x1 = static_cast<int>((ix + 1) & mask);
  const int y0 = static_cast<int>(iy & mask), y1 = static_cast<int>((iy + 1) & mask);
  const float* r0 = m.ptr<float>(y0);
  const float* r1 = m.ptr<float>(y1);
  const float top = r0[x0] + ax * (r0[x1] - r0[x0]);
  const float bottom = r1[x0] + ax * (r1[x1] - r1[x0]);
  return top + ay * (bottom - top);
}

float Texture::Sample(double x, double y, float lod) const {
  if (lod <= 0.f) return SampleLevel(0, x, y);
  const int last = levels() - 1;
  if (lod >= static_cast<float>(last)) return SampleLevel(last, x, y);
  const int l0 = static_cast<int>(lod);
  const float a = lod - static_cast<float>(l0);
  const float v0 = SampleLevel(l0, x, y);
  if (a < 1e-3f) return v0;
  return v0 + a * (SampleLevel(l0 + 1, x, y) - v0);
}

cv::Mat MakeTextureImage(uint64_t seed, TextureStyle style, int side) {
  CHECK(IsPowerOfTwo(side) && side >= 64) << "texture side must be a power of two >= 64";
  Rng rng(MixSeed(seed, 0x7E7));
  const double s = side / 1024.0;  // Shape sizes are designed for a 1024 texture.
  cv::Mat img(side, side, CV_8UC1);
  if (style == TextureStyle::kRich) {
    // Background: large soft blobs so no region is flat.
    img = SmoothBackground(rng, side, rng.Uniform(90, 160), 60, 200, 40, 12.0);
    // Four scales of crisp shapes, contrast increasing toward the small scales.
    struct Layer {
      int count;
      double radius;
    };
    const Layer layers[] = {{60, 110 * s}, {350, 45 * s}, {1600, 16 * s}, {2500, 6 * s}};
    for (const Layer& layer : layers) {
      const int count = static_cast<int>(layer.count * s * s);
      for (int i = 0; i < count; ++i) {
        DrawRandomShape(rng, img, layer.radius * rng.Uniform(0.6, 1.4), 15, 240, true);
      }
    }
    // Slight optical blur: crisp but not aliased corners.
    img = BlurWrap(img, 0.8);
  } else {
    // Weak texture: a smooth shading plus sparse, low-contrast shapes.
    const double base = rng.Uniform(110, 150);
    img = SmoothBackground(rng, side, base, base - 25, base + 25, 12, 25.0);
    const int count = static_cast<int>(700 * s * s);
    for (int i = 0; i < count; ++i) {
      const double g =
          rng.Uniform() < 0.5 ? base - rng.Uniform(25, 55) : base + rng.Uniform(25, 55);
      DrawRandomShape(rng, img, 14 * s * rng.Uniform(0.6, 1.6), g, g + 1, true);
    }
    img = BlurWrap(img, 1.0);
  }
  return img;
}

}  // namespace dala::sim
