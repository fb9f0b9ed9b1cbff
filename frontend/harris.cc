#include "frontend/harris.h"

#include <glog/logging.h>

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

namespace dala {

bool HarrisOptions::IsValid(std::string* why) const {
  auto fail = [&](const std::string& msg) {
    if (why != nullptr) *why = msg;
    return false;
  };
  if (!(sigma_d > 0.0)) return fail("sigma_d must be > 0");
  if (!(sigma_i > 0.0)) return fail("sigma_i must be > 0");
  if (!(k > 0.0 && k < 0.25)) return fail("k must be in (0, 0.25)");
  if (!(relative_threshold >= 0.0 && relative_threshold < 1.0))
    return fail("relative_threshold must be in [0, 1)");
  if (!(min_cornerness >= 0.0)) return fail("min_cornerness must be >= 0");
  if (!(min_eigen_ratio >= 0.0 && min_eigen_ratio <= 1.0))
    return fail("min_eigen_ratio must be in [0, 1]");
  if (num_levels < 1 || num_levels > 10) return fail("num_levels must be in [1, 10]");
  if (!(scale_factor > 1.0 && scale_factor <= 4.0)) return fail("scale_factor must be in (1, 4]");
  if (cell_size < 0) return fail("cell_size must be >= 0 (0 disables bucketing)");
  if (max_per_cell < 1) return fail("max_per_cell must be >= 1");
  if (max_points < 1) return fail("max_points must be >= 1");
  if (border < 1) return fail("border must be >= 1");
  if (!(sigma_orientation > 0.0)) return fail("sigma_orientation must be > 0");
  if (patch_size < 3 || patch_size % 2 == 0) return fail("patch_size must be odd and >= 3");
  if (!(patch_spacing > 0.0)) return fail("patch_spacing must be > 0");
  return true;
}

namespace {

struct Candidate {
  int x, y;
  float r;
};

// Gaussian-weighted mean gradient around (x, y): the gradient of S blurred once more, i.e. the
// dominant gradient direction of the neighbourhood. `weights` is the (2r+1)^2 Gaussian window.
// Returns atan2(g_y, g_x).
float MeanGradientOrientation(const cv::Mat& ix, const cv::Mat& iy, int x, int y,
                              const std::vector<float>& weights, int r) {
  float gx = 0.f, gy = 0.f;
  const float* w = weights.data();
  for (int dy = -r; dy <= r; ++dy, w += 2 * r + 1) {
    const int yy = y + dy;
    if (yy < 0 || yy >= ix.rows) continue;
    const float* px = ix.ptr<float>(yy);
    const float* py = iy.ptr<float>(yy);
    const int x0 = std::max(-r, -x), x1 = std::min(r, ix.cols - 1 - x);
    for (int dx = x0; dx <= x1; ++dx) {
      gx += w[dx + r] * px[x + dx];
      gy += w[dx + r] * py[x + dx];
    }
  }
  return std::atan2(gy, gx);
}

// Gaussian kernel size covering +-2.5 sigma (OpenCV's default for float covers +-4 sigma, which
// costs 60 % more for a negligible difference in the response).
cv::Size KernelSize(double sigma) {
  const int k = 2 * static_cast<int>(std::ceil(2.5 * sigma)) + 1;
  return cv::Size(k, k);
}

// Per-thread scratch images reused across calls: fresh multi-megabyte buffers on every call
// cost more in page faults than the filtering itself.
struct Workspace {
  cv::Mat ix, iy, product, mxx, mxy, myy, response, dilated;
};

// Detects the points of one level and appends them (level-0 coordinates) to `out`.
void DetectLevel(const cv::Mat& smoothed, const PyramidLevel& level, int level_index,
                 const HarrisOptions& options, std::vector<InterestPoint>* out) {
  thread_local std::vector<Workspace> workspaces;
  if (static_cast<int>(workspaces.size()) <= level_index) workspaces.resize(level_index + 1);
  Workspace& ws = workspaces[level_index];
  // Derivatives of Gaussian: central differences of the Gaussian-smoothed image.
  cv::Mat& ix = ws.ix;
  cv::Mat& iy = ws.iy;
  cv::Sobel(smoothed, ix, CV_32F, 1, 0, 1, 0.5, 0.0, cv::BORDER_REFLECT_101);
  cv::Sobel(smoothed, iy, CV_32F, 0, 1, 1, 0.5, 0.0, cv::BORDER_REFLECT_101);
  // Gaussian-weighted auto-correlation products.
  // Products into a scratch image, blurred into their own buffer: OpenCV copies the source of
  // an in-place filter first.
  const cv::Size ksize_i = KernelSize(options.sigma_i);
  cv::Mat& mxx = ws.mxx;
  cv::Mat& mxy = ws.mxy;
  cv::Mat& myy = ws.myy;
  cv::multiply(ix, ix, ws.product);
  cv::GaussianBlur(ws.product, mxx, ksize_i, options.sigma_i, options.sigma_i,
                   cv::BORDER_REFLECT_101);
  cv::multiply(ix, iy, ws.product);
  cv::GaussianBlur(ws.product, mxy, ksize_i, options.sigma_i, options.sigma_i,
                   cv::BORDER_REFLECT_101);
  cv::multiply(iy, iy, ws.product);
  cv::GaussianBlur(ws.product, myy, ksize_i, options.sigma_i, options.sigma_i,
                   cv::BORDER_REFLECT_101);
  cv::Mat& response = ws.response;
  response.create(smoothed.size(), CV_32F);
  const float k = static_cast<float>(options.k);
  float max_r = 0.f;
  for (int y = 0; y < smoothed.rows; ++y) {
    const float* pa = mxx.ptr<float>(y);
    const float* pb = mxy.ptr<float>(y);
    const float* pc = myy.ptr<float>(y);
    float* pr = response.ptr<float>(y);
    for (int x = 0; x < smoothed.cols; ++x) {
      const float a = pa[x], b = pb[x], c = pc[x];
      const float tr = a + c;
      pr[x] = a * c - b * b - k * tr * tr;
      max_r = std::max(max_r, pr[x]);
    }
  }
  const float threshold = std::max(static_cast<float>(options.min_cornerness),
                                   static_cast<float>(options.relative_threshold) * max_r);
  cv::Mat& dilated = ws.dilated;
  cv::dilate(response, dilated, cv::Mat());  // 3x3 maximum filter.

  std::vector<Candidate> candidates;
  const int b = std::max(options.border, 1);
  for (int y = b; y < response.rows - b; ++y) {
    const float* pr = response.ptr<float>(y);
    const float* pd = dilated.ptr<float>(y);
    for (int x = b; x < response.cols - b; ++x) {
      if (pr[x] > threshold && pr[x] >= pd[x]) candidates.push_back({x, y, pr[x]});
    }
  }
  std::sort(candidates.begin(), candidates.end(), [](const Candidate& l, const Candidate& r) {
    return l.r > r.r || (l.r == r.r && (l.y < r.y || (l.y == r.y && l.x < r.x)));
  });

  // Bucketing: the strongest max_per_cell maxima of each cell survive.
  const int cell = options.cell_size;
  const int cells_x = cell > 0 ? (response.cols + cell - 1) / cell : 1;
  const int cells_y = cell > 0 ? (response.rows + cell - 1) / cell : 1;
  std::vector<int> count(static_cast<size_t>(cells_x) * cells_y, 0);
  const int r_o = static_cast<int>(std::ceil(2.5 * options.sigma_orientation));
  std::vector<float> weights;
  for (int dy = -r_o; dy <= r_o; ++dy) {
    for (int dx = -r_o; dx <= r_o; ++dx) {
      weights.push_back(static_cast<float>(std::exp(
          -(dx * dx + dy * dy) / (2.0 * options.sigma_orientation * options.sigma_orientation))));
    }
  }
  const float min_ratio = static_cast<float>(options.min_eigen_ratio);
  for (const Candidate& c : candidates) {
    // Edge-like maxima: lambda2 / lambda1 from R = l1 l2 - k (l1 + l2)^2 and the trace.
    const float ma = mxx.at<float>(c.y, c.x), mc = myy.at<float>(c.y, c.x);
    const float mb = mxy.at<float>(c.y, c.x);
    const float half_t = 0.5f * (ma + mc);
    const float dsc = std::sqrt(std::max(0.f, half_t * half_t - (ma * mc - mb * mb)));
    if (half_t - dsc < min_ratio * (half_t + dsc)) continue;
    // Sub-pixel: extremum of the quadratic through the 3x3 neighbourhood of R,
    // offset = -H^-1 g with central-difference gradient g and Hessian H.
    // The fit is made on log R when R > 0 on the whole 3x3: the response peak is close to a
    // Gaussian, for which the log-parabola is exact (a parabola on R itself is biased by up to
    // 0.15 px on a symmetric junction).
    bool use_log = true;
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dx = -1; dx <= 1; ++dx) use_log &= response.at<float>(c.y + dy, c.x + dx) > 0.f;
    }
    auto R = [&](int dx, int dy) {
      const double r = response.at<float>(c.y + dy, c.x + dx);
      return use_log ? std::log(r) : r;
    };
    const double gx = 0.5 * (R(1, 0) - R(-1, 0));
    const double gy = 0.5 * (R(0, 1) - R(0, -1));
    const double hxx = R(1, 0) - 2.0 * R(0, 0) + R(-1, 0);
    const double hyy = R(0, 1) - 2.0 * R(0, 0) + R(0, -1);
    const double hxy = 0.25 * (R(1, 1) - R(1, -1) - R(-1, 1) + R(-1, -1));
    const double det = hxx * hyy - hxy * hxy;
    double ox = 0.0, oy = 0.0;
    if (det > 1e-12 * (hxx * hxx + hyy * hyy) && hxx < 0.0) {  // A maximum: H negative definite.
      ox = -(hyy * gx - hxy * gy) / det;
      oy = -(hxx * gy - hxy * gx) / det;
      if (std::abs(ox) > 0.75 || std::abs(oy) > 0.75) ox = oy = 0.0;  // Fit not trustworthy.
    }
    if (cell > 0) {  // Bucket of the refined position (pixel x covers [x - 0.5, x + 0.5)).
      const int bx =
          std::clamp(static_cast<int>(std::floor((c.x + ox + 0.5) / cell)), 0, cells_x - 1);
      const int by =
          std::clamp(static_cast<int>(std::floor((c.y + oy + 0.5) / cell)), 0, cells_y - 1);
      int& n = count[static_cast<size_t>(by) * cells_x + bx];
      if (n >= options.max_per_cell) continue;
      ++n;
    }
    const double m0 = mxx.at<float>(c.y, c.x), m1 = mxy.at<float>(c.y, c.x);
    const double m2 = myy.at<float>(c.y, c.x);
    const double half_tr = 0.5 * (m0 + m2);
    const double disc = std::sqrt(std::max(0.0, half_tr * half_tr - (m0 * m2 - m1 * m1)));
    InterestPoint p;
    p.uv = Eigen::Vector2d((c.x + ox) * level.scale_x + level.offset_x,
                           (c.y + oy) * level.scale_y + level.offset_y);
    p.cornerness = c.r;
    p.lambda1 = static_cast<float>(half_tr + disc);
    p.lambda2 = static_cast<float>(half_tr - disc);
    p.orientation = MeanGradientOrientation(ix, iy, c.x, c.y, weights, r_o);
    p.scale = static_cast<float>(0.5 * (level.scale_x + level.scale_y));
    p.level = level_index;
    out->push_back(p);
  }
}

inline float Bilinear(const cv::Mat& img, double x, double y) {
  x = std::clamp(x, 0.0, img.cols - 1.001);
  y = std::clamp(y, 0.0, img.rows - 1.001);
  const int x0 = static_cast<int>(x), y0 = static_cast<int>(y);
  const float fx = static_cast<float>(x - x0), fy = static_cast<float>(y - y0);
  const float* r0 = img.ptr<float>(y0);
  const float* r1 = img.ptr<float>(y0 + 1);
  return (1.f - fy) * ((1.f - fx) * r0[x0] + fx * r0[x0 + 1]) +
         fy * ((1.f - fx) * r1[x0] + fx * r1[x0 + 1]);
}

}  // namespace

bool SamplePatch(const DetectedImage& image, const Eigen::Vector2d& uv, double orientation,
                 double scale, float* out) {
  CHECK(!image.pyramid.empty()) << "SamplePatch needs a DetectedImage from DetectHarris";
  // Level whose scale is closest (in log) to the requested one.
  int best = 0;
  double best_d = 1e9;
  for (size_t l = 0; l < image.pyramid.size(); ++l) {
    const double s = 0.5 * (image.pyramid[l].scale_x + image.pyramid[l].scale_y);
    const double d = std::abs(std::log(scale / s));
    if (d < best_d) best_d = d, best = static_cast<int>(l);
  }
  const PyramidLevel& level = image.pyramid[best];
  const double level_scale = 0.5 * (level.scale_x + level.scale_y);
  const double cx = (uv.x() - level.offset_x) / level.scale_x;
  const double cy = (uv.y() - level.offset_y) / level.scale_y;
  const double step = image.patch_spacing * scale / level_scale;
  const double c = std::cos(orientation) * step, s = std::sin(orientation) * step;
  const int h = image.patch_size / 2;
  const int n = image.patch_size * image.patch_size;
  double sum = 0.0, sum2 = 0.0;
  int idx = 0;
  const cv::Mat& img = level.smoothed;
  const double reach = (std::abs(c) + std::abs(s)) * h + 1.0;
  if (cx - reach >= 0.0 && cy - reach >= 0.0 && cx + reach < img.cols - 1 &&
      cy + reach < img.rows - 1) {
    // Fast path: the whole patch is inside, no clamping.
    const size_t stride = img.step1();
    const float* base = img.ptr<float>();
    for (int b = -h; b <= h; ++b) {
      double x = cx - c * h - s * b, y = cy - s * h + c * b;
      for (int a = -h; a <= h; ++a, x += c, y += s) {
        const int x0 = static_cast<int>(x), y0 = static_cast<int>(y);
        const float fx = static_cast<float>(x - x0), fy = static_cast<float>(y - y0);
        const float* r0 = base + y0 * stride + x0;
        const float* r1 = r0 + stride;
        const float v =
            (1.f - fy) * ((1.f - fx) * r0[0] + fx * r0[1]) + fy * ((1.f - fx) * r1[0] + fx * r1[1]);
        out[idx++] = v;
        sum += v;
        sum2 += static_cast<double>(v) * v;
      }
    }
  } else {
    for (int b = -h; b <= h; ++b) {
      for (int a = -h; a <= h; ++a) {
        const float v = Bilinear(img, cx + c * a - s * b, cy + s * a + c * b);
        out[idx++] = v;
        sum += v;
        sum2 += static_cast<double>(v) * v;
      }
    }
  }
  const double mean = sum / n;
  const double var = sum2 / n - mean * mean;
  if (var < 1e-4) {
    std::fill(out, out + n, 0.f);
    return false;
  }
  const float inv = static_cast<float>(1.0 / std::sqrt(var * n));
  for (int i = 0; i < n; ++i) out[i] = static_cast<float>((out[i] - mean) * inv);
  return true;
}

DetectedImage DetectHarris(const cv::Mat& gray, const HarrisOptions& options) {
  std::string why;
  CHECK(options.IsValid(&why)) << "Invalid HarrisOptions: " << why;
  CHECK(!gray.empty() && gray.type() == CV_8UC1) << "DetectHarris needs a CV_8UC1 image";
  DetectedImage result;
  result.image_size = gray.size();
  result.patch_size = options.patch_size;
  result.patch_spacing = options.patch_spacing;

  // Levels: cascaded area resizing by scale_factor; with the default sqrt(2), level l >= 2 is
  // cv::pyrDown of level l - 2 instead (exact factor 2, ten times cheaper than INTER_AREA at a
  // non-integer ratio).
  const bool sqrt2 = std::abs(options.scale_factor * options.scale_factor - 2.0) < 1e-6;
  std::vector<cv::Mat> levels_u8;
  for (int l = 0; l < options.num_levels; ++l) {
    cv::Mat level_u8;
    if (l == 0) {
      level_u8 = gray;
    } else if (sqrt2 && l >= 2) {
      cv::pyrDown(levels_u8[l - 2], level_u8);
    } else {
      const cv::Mat& prev = levels_u8[l - 1];
      const cv::Size size(static_cast<int>(std::lround(prev.cols / options.scale_factor)),
                          static_cast<int>(std::lround(prev.rows / options.scale_factor)));
      cv::resize(prev, level_u8, size, 0, 0, cv::INTER_AREA);
    }
    if (level_u8.cols < 4 * options.border || level_u8.rows < 4 * options.border) break;
    levels_u8.push_back(level_u8);
    // Compose the level -> level-0 affine map. cv::resize (INTER_AREA) with ratio r maps pixel
    // centres as u_src = r (u + 0.5) - 0.5; cv::pyrDown as u_src = 2 u (its kernel is centred on
    // the even source pixels).
    PyramidLevel level;
    if (l > 0) {
      const bool pyr = sqrt2 && l >= 2;
      const PyramidLevel& src = result.pyramid[pyr ? l - 2 : l - 1];
      const cv::Mat& src_u8 = levels_u8[pyr ? l - 2 : l - 1];
      const double rx = pyr ? 2.0 : static_cast<double>(src_u8.cols) / level_u8.cols;
      const double ry = pyr ? 2.0 : static_cast<double>(src_u8.rows) / level_u8.rows;
      const double bx = pyr ? 0.0 : 0.5 * rx - 0.5, by = pyr ? 0.0 : 0.5 * ry - 0.5;
      level.scale_x = src.scale_x * rx;
      level.scale_y = src.scale_y * ry;
      level.offset_x = src.scale_x * bx + src.offset_x;
      level.offset_y = src.scale_y * by + src.offset_y;
    }
    thread_local cv::Mat level_f32;  // Scratch (a filter in place would copy its source).
    level_u8.convertTo(level_f32, CV_32F);
    cv::GaussianBlur(level_f32, level.smoothed, KernelSize(options.sigma_d), options.sigma_d,
                     options.sigma_d, cv::BORDER_REFLECT_101);
    DetectLevel(level.smoothed, level, l, options, &result.points);
    result.pyramid.push_back(std::move(level));
  }
  if (static_cast<int>(result.points.size()) > options.max_points) {
    // Cornerness grows like scale^4 across levels (gradients per level pixel); compare the
    // scale-normalised value so that the cap does not favour coarse levels.
    std::stable_sort(result.points.begin(), result.points.end(),
                     [](const InterestPoint& a, const InterestPoint& b) {
                       const float sa = a.scale * a.scale, sb = b.scale * b.scale;
                       return a.cornerness / (sa * sa) > b.cornerness / (sb * sb);
                     });
    result.points.resize(options.max_points);
  }

  const int n = options.patch_size * options.patch_size;
  result.descriptors.create(static_cast<int>(result.points.size()), n, CV_32F);
  for (size_t i = 0; i < result.points.size(); ++i) {
    const InterestPoint& p = result.points[i];
    SamplePatch(result, p.uv, p.orientation, p.scale, result.descriptors.ptr<float>(i));
  }
  return result;
}

}  // namespace dala
