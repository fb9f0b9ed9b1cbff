#include "frontend/harris.h"

#include "frontend/worker_thread.h"

#include <glog/logging.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
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
// dominant gradient direction of the neighbourhood. The gradient is the central difference of S
// (the same I_x, I_y as the auto-correlation; the window stays inside the image for points
// farther than r + 1 from the border, and is cut at the border otherwise). `weights` is the
// (2r+1)^2 Gaussian window. Returns atan2(g_y, g_x).
float MeanGradientOrientation(const cv::Mat& smoothed, int x, int y,
                              const std::vector<float>& weights, int r) {
  float gx = 0.f, gy = 0.f;
  const float* w = weights.data();
  const int cols = smoothed.cols, rows = smoothed.rows;
  constexpr int kMaxSide = 64;
  const int side = 2 * r + 1;
  if (side <= kMaxSide && x - r >= 1 && x + r <= cols - 2 && y - r >= 1 && y + r <= rows - 2) {
    // Inside the image (no border case): the window is summed column by column first, so the
    // inner loop has independent lanes and vectorises (a single running sum is a chain of
    // dependent additions). The factor 1/2 of the central differences does not change atan2.
    float col_x[kMaxSide] = {}, col_y[kMaxSide] = {};
    const size_t stride = smoothed.step1();
    const float* s = smoothed.ptr<float>(y - r) + (x - r);
    for (int dy = 0; dy < side; ++dy, w += side, s += stride) {
      const float* up = s - stride;
      const float* dn = s + stride;
      for (int i = 0; i < side; ++i) {
        col_x[i] += w[i] * (s[i + 1] - s[i - 1]);
        col_y[i] += w[i] * (dn[i] - up[i]);
      }
    }
    for (int i = 0; i < side; ++i) {
      gx += col_x[i];
      gy += col_y[i];
    }
    return std::atan2(gy, gx);
  }
  for (int dy = -r; dy <= r; ++dy, w += 2 * r + 1) {
    const int yy = y + dy;
    if (yy < 0 || yy >= rows) continue;
    // BORDER_REFLECT_101 central differences: zero on the first and last row / column.
    const float* s = smoothed.ptr<float>(yy);
    const float* s_up = smoothed.ptr<float>(yy > 0 ? yy - 1 : 1);
    const float* s_dn = smoothed.ptr<float>(yy < rows - 1 ? yy + 1 : rows - 2);
    const int x0 = std::max(-r, -x), x1 = std::min(r, cols - 1 - x);
    for (int dx = x0; dx <= x1; ++dx) {
      const int xx = x + dx;
      const float ix = (xx == 0 || xx == cols - 1) ? 0.f : 0.5f * (s[xx + 1] - s[xx - 1]);
      gx += w[dx + r] * ix;
      gy += w[dx + r] * 0.5f * (s_dn[xx] - s_up[xx]);
    }
  }
  return std::atan2(gy, gx);
}

// Gaussian kernel size covering +-2.5 sigma (OpenCV's default for float covers +-4 sigma, which
// costs 60 % more for a negligible difference in the response).
int KernelSide(double sigma) { return 2 * static_cast<int>(std::ceil(2.5 * sigma)) + 1; }

// Per-thread scratch images reused across calls: fresh multi-megabyte buffers on every call
// cost more in page faults than the filtering itself.
struct Workspace {
  cv::Mat pxx, pxy, pyy;  // CV_32F gradient products I_x^2, I_x I_y, I_y^2.
  cv::Mat mxx, mxy, myy;  // CV_32F G(sigma_i) * products.
  cv::Mat response;       // CV_32F R.
  std::vector<Candidate> candidates;
  std::vector<uint8_t> row_mask;
};

// mask[x] = 1 where row[x] > threshold and row[x] >= both horizontal neighbours, for x in
// [x0, x1) (x0 >= 1, x1 <= width - 1); branch-free so that it vectorises.
void HorizontalMaxima(const float* __restrict row, int x0, int x1, float threshold,
                      uint8_t* __restrict mask) {
  for (int x = x0; x < x1; ++x) {
    const float r = row[x];
    mask[x] = static_cast<uint8_t>((r > threshold) & (r >= row[x - 1]) & (r >= row[x + 1]));
  }
}

// One row of gradient products for columns 1 .. n - 2 (s: the row of S, up / dn: its neighbours).
void GradientProductsRow(const float* __restrict s, const float* __restrict up,
                         const float* __restrict dn, int n, float* __restrict pxx,
                         float* __restrict pxy, float* __restrict pyy) {
  for (int x = 1; x < n - 1; ++x) {
    const float ix = 0.5f * (s[x + 1] - s[x - 1]);
    const float iy = 0.5f * (dn[x] - up[x]);
    pxx[x] = ix * ix;
    pxy[x] = ix * iy;
    pyy[x] = iy * iy;
  }
}

// The gradient products of the central differences of `smoothed` with BORDER_REFLECT_101 (the
// derivative is zero on the first / last row and column), in one pass over planar images (the
// inner loop vectorises; no I_x, I_y images are stored).
void GradientProducts(const cv::Mat& smoothed, Workspace* ws) {
  const int rows = smoothed.rows, cols = smoothed.cols;
  ws->pxx.create(rows, cols, CV_32F);
  ws->pxy.create(rows, cols, CV_32F);
  ws->pyy.create(rows, cols, CV_32F);
  for (int y = 0; y < rows; ++y) {
    const float* s = smoothed.ptr<float>(y);
    const float* s_up = smoothed.ptr<float>(y > 0 ? y - 1 : std::min(1, rows - 1));
    const float* s_dn = smoothed.ptr<float>(y < rows - 1 ? y + 1 : std::max(rows - 2, 0));
    float* pxx = ws->pxx.ptr<float>(y);
    float* pxy = ws->pxy.ptr<float>(y);
    float* pyy = ws->pyy.ptr<float>(y);
    GradientProductsRow(s, s_up, s_dn, cols, pxx, pxy, pyy);
    for (const int x : {0, cols - 1}) {
      const float iy = 0.5f * (s_dn[x] - s_up[x]);
      pxx[x] = 0.f;
      pxy[x] = 0.f;
      pyy[x] = iy * iy;
    }
  }
}

// Detects the points of one level and appends them (level-0 coordinates) to `out`.
void DetectLevel(const cv::Mat& smoothed, const PyramidLevel& level, int level_index,
                 const HarrisOptions& options, std::vector<InterestPoint>* out) {
  thread_local std::vector<Workspace> workspaces;
  if (static_cast<int>(workspaces.size()) <= level_index) workspaces.resize(level_index + 1);
  Workspace& ws = workspaces[level_index];
  // Gaussian-weighted auto-correlation products.
  GradientProducts(smoothed, &ws);
  const int side_i = KernelSide(options.sigma_i);
  const cv::Mat kernel_i = cv::getGaussianKernel(side_i, options.sigma_i, CV_32F);
  for (const auto& [src, dst] :
       {std::pair<cv::Mat*, cv::Mat*>{&ws.pxx, &ws.mxx}, {&ws.pxy, &ws.mxy}, {&ws.pyy, &ws.myy}}) {
    cv::sepFilter2D(*src, *dst, CV_32F, kernel_i, kernel_i, cv::Point(-1, -1), 0.0,
                    cv::BORDER_REFLECT_101);
  }
  const cv::Mat& mxx = ws.mxx;
  const cv::Mat& mxy = ws.mxy;
  const cv::Mat& myy = ws.myy;
  cv::Mat& response = ws.response;
  response.create(smoothed.size(), CV_32F);
  const float k = static_cast<float>(options.k);
  for (int y = 0; y < smoothed.rows; ++y) {
    const float* __restrict pa = mxx.ptr<float>(y);
    const float* __restrict pb = mxy.ptr<float>(y);
    const float* __restrict pc = myy.ptr<float>(y);
    float* __restrict pr = response.ptr<float>(y);
    for (int x = 0; x < smoothed.cols; ++x) {
      const float tr = pa[x] + pc[x];
      pr[x] = pa[x] * pc[x] - pb[x] * pb[x] - k * tr * tr;
    }
  }
  double max_r = 0.0;
  cv::minMaxIdx(response, nullptr, &max_r);
  const float threshold =
      std::max(static_cast<float>(options.min_cornerness),
               static_cast<float>(options.relative_threshold) * std::max(0.f, float(max_r)));

  // 3x3 maxima above the threshold: R >= its 8 neighbours (border >= 1 keeps them inside).
  // A vectorised pass marks the row's horizontal maxima above the threshold; only those are
  // compared with the rows above and below.
  std::vector<Candidate>& candidates = ws.candidates;
  candidates.clear();
  const int b = std::max(options.border, 1);
  const size_t stride = response.step1();
  ws.row_mask.resize(response.cols);
  for (int y = b; y < response.rows - b; ++y) {
    const float* pr = response.ptr<float>(y);
    HorizontalMaxima(pr, b, response.cols - b, threshold, ws.row_mask.data());
    const uint8_t* mask = ws.row_mask.data();
    const int x_end = response.cols - b;
    for (int x = b; x < x_end; ++x) {
      if (x + 8 <= x_end) {  // Skip eight unmarked pixels at once.
        uint64_t word;
        std::memcpy(&word, mask + x, sizeof(word));
        if (word == 0) {
          x += 7;
          continue;
        }
      }
      if (!mask[x]) continue;
      const float r = pr[x];
      const float* up = pr + x - stride;
      const float* dn = pr + x + stride;
      if (r >= up[-1] && r >= up[0] && r >= up[1] && r >= dn[-1] && r >= dn[0] && r >= dn[1]) {
        candidates.push_back({x, y, r});
      }
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
  weights.reserve(static_cast<size_t>(2 * r_o + 1) * (2 * r_o + 1));
  for (int dy = -r_o; dy <= r_o; ++dy) {
    for (int dx = -r_o; dx <= r_o; ++dx) {
      weights.push_back(static_cast<float>(std::exp(
          -(dx * dx + dy * dy) / (2.0 * options.sigma_orientation * options.sigma_orientation))));
    }
  }
  const float min_ratio = static_cast<float>(options.min_eigen_ratio);
  for (const Candidate& c : candidates) {
    // Edge-like maxima: lambda2 / lambda1 from R = l1 l2 - k (l1 + l2)^2 and the trace.
    const float ma = mxx.at<float>(c.y, c.x), mb = mxy.at<float>(c.y, c.x);
    const float mc = myy.at<float>(c.y, c.x);
    const float half_t = 0.5f * (ma + mc);
    const float dsc = std::sqrt(std::max(0.f, half_t * half_t - (ma * mc - mb * mb)));
    if (half_t - dsc < min_ratio * (half_t + dsc)) continue;
    // Sub-pixel: extremum of the quadratic through the 3x3 neighbourhood of R,
    // offset = -H^-1 g with central-difference gradient g and Hessian H.
    // The fit is made on log R when R > 0 on the whole 3x3: the response peak is close to a
    // Gaussian, for which the log-parabola is exact (a parabola on R itself is biased by up to
    // 0.15 px on a symmetric junction).
    double nb[3][3];
    bool use_log = true;
    for (int dy = -1; dy <= 1; ++dy) {
      const float* pr = response.ptr<float>(c.y + dy) + c.x;
      for (int dx = -1; dx <= 1; ++dx) {
        nb[dy + 1][dx + 1] = pr[dx];
        use_log &= pr[dx] > 0.f;
      }
    }
    if (use_log) {
      for (auto& row : nb) {
        for (double& v : row) v = std::log(v);
      }
    }
    auto R = [&](int dx, int dy) { return nb[dy + 1][dx + 1]; };
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
    const double m0 = ma, m1 = mb, m2 = mc;
    const double half_tr = 0.5 * (m0 + m2);
    const double disc = std::sqrt(std::max(0.0, half_tr * half_tr - (m0 * m2 - m1 * m1)));
    InterestPoint p;
    p.uv = Eigen::Vector2d((c.x + ox) * level.scale_x + level.offset_x,
                           (c.y + oy) * level.scale_y + level.offset_y);
    p.cornerness = c.r;
    p.lambda1 = static_cast<float>(half_tr + disc);
    p.lambda2 = static_cast<float>(half_tr - disc);
    p.orientation = MeanGradientOrientation(smoothed, c.x, c.y, weights, r_o);
    p.scale = static_cast<float>(0.5 * (level.scale_x + level.scale_y));
    p.level = level_index;
    out->push_back(p);
  }
}

// Area (box) reduction of n_src pixels to n_dst: destination pixel d averages the source
// interval [d r, (d + 1) r), r = n_src / n_dst, each source pixel weighted by its overlap
// (cv::INTER_AREA's definition, without its rounding to 8 bits). Flat tables of `taps` entries
// per destination pixel (unused ones: weight 0 on the first source pixel).
struct AreaTaps {
  int taps = 0;
  std::vector<int> src;
  std::vector<float> weight;
};
AreaTaps MakeAreaTaps(int n_src, int n_dst) {
  const double r = static_cast<double>(n_src) / n_dst;
  AreaTaps t;
  t.taps = static_cast<int>(std::ceil(r)) + 1;
  t.src.assign(static_cast<size_t>(n_dst) * t.taps, 0);
  t.weight.assign(static_cast<size_t>(n_dst) * t.taps, 0.f);
  for (int d = 0; d < n_dst; ++d) {
    const double lo = d * r, hi = std::min((d + 1) * r, static_cast<double>(n_src));
    const size_t base = static_cast<size_t>(d) * t.taps;
    double sum = 0.0;
    int used = 0;
    for (int i = static_cast<int>(std::floor(lo)); i < hi && i < n_src; ++i) {
      const double overlap = std::min(hi, i + 1.0) - std::max(lo, static_cast<double>(i));
      if (overlap > 1e-3 && used < t.taps) {
        t.src[base + used] = i;
        t.weight[base + used] = static_cast<float>(overlap);
        sum += overlap;
        ++used;
      }
    }
    for (int k = 0; k < used; ++k)
      t.weight[base + k] = static_cast<float>(t.weight[base + k] / sum);
    for (int k = used; k < t.taps; ++k) t.src[base + k] = t.src[base];
  }
  return t;
}

// Area reduction of a CV_8U or CV_32F image to `size` (each axis reduced), as float: a vertical
// pass (whole rows, vectorised) then a horizontal one of ceil(r) + 1 taps. cv::resize(INTER_AREA)
// takes its generic, unvectorised path at a non-integer ratio such as sqrt(2) and cost more than
// all the filtering of the level.
void AreaResize(const cv::Mat& src, cv::Size size, cv::Mat* dst) {
  CHECK(src.type() == CV_8UC1 || src.type() == CV_32FC1);
  CHECK(size.width <= src.cols && size.height <= src.rows && size.area() > 0);
  const AreaTaps tx = MakeAreaTaps(src.cols, size.width);
  const AreaTaps ty = MakeAreaTaps(src.rows, size.height);
  thread_local cv::Mat src_f32, vertical;
  const cv::Mat* in = &src;
  if (src.depth() == CV_8U) {
    src.convertTo(src_f32, CV_32F);
    in = &src_f32;
  }
  vertical.create(size.height, src.cols, CV_32F);
  for (int y = 0; y < size.height; ++y) {
    float* __restrict out = vertical.ptr<float>(y);
    std::fill(out, out + src.cols, 0.f);
    for (int k = 0; k < ty.taps; ++k) {
      const float w = ty.weight[static_cast<size_t>(y) * ty.taps + k];
      if (w == 0.f) continue;
      const float* __restrict row = in->ptr<float>(ty.src[static_cast<size_t>(y) * ty.taps + k]);
      for (int x = 0; x < src.cols; ++x) out[x] += w * row[x];
    }
  }
  dst->create(size, CV_32F);
  for (int y = 0; y < size.height; ++y) {
    const float* row = vertical.ptr<float>(y);
    float* out = dst->ptr<float>(y);
    const int* s = tx.src.data();
    const float* w = tx.weight.data();
    if (tx.taps == 3) {  // Ratios in (1, 2], e.g. sqrt(2): unrolled.
      for (int x = 0; x < size.width; ++x, s += 3, w += 3) {
        out[x] = w[0] * row[s[0]] + w[1] * row[s[1]] + w[2] * row[s[2]];
      }
    } else {
      for (int x = 0; x < size.width; ++x) {
        float v = 0.f;
        for (int k = 0; k < tx.taps; ++k, ++s, ++w) v += *w * row[*s];
        out[x] = v;
      }
    }
  }
}

// A CV_32F image of `size` for a result that outlives the call (a pyramid level kept in the
// DetectedImage), reusing a buffer of this thread's pool that nothing references any more (its
// DetectedImage was destroyed). Fresh multi-megabyte buffers on every frame cost ~1000 page
// faults per image, as much time as the whole level's filtering; a frontend keeps a few
// DetectedImages alive at a time, so a small pool recycles them all.
cv::Mat RecycledImage(cv::Size size) {
  constexpr size_t kMaxPooled = 16;
  thread_local std::vector<cv::Mat> pool;
  const auto unused = [](const cv::Mat& m) {
    return m.u != nullptr && __atomic_load_n(&m.u->refcount, __ATOMIC_ACQUIRE) == 1;
  };
  cv::Mat* spare = nullptr;
  for (cv::Mat& m : pool) {
    if (!unused(m)) continue;
    if (m.size() == size) return m;
    spare = &m;
  }
  cv::Mat fresh(size, CV_32F);
  if (spare != nullptr) {
    *spare = fresh;  // Drop an unused buffer of another size.
  } else if (pool.size() < kMaxPooled) {
    pool.push_back(fresh);
  }
  return fresh;
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

DetectedImage DetectHarris(const cv::Mat& gray, const HarrisOptions& options,
                           WorkerThread* helper) {
  std::string why;
  CHECK(options.IsValid(&why)) << "Invalid HarrisOptions: " << why;
  CHECK(!gray.empty() && gray.type() == CV_8UC1) << "DetectHarris needs a CV_8UC1 image";
  DetectedImage result;
  result.image_size = gray.size();
  result.patch_size = options.patch_size;
  result.patch_spacing = options.patch_spacing;

  // 1. The pyramid's grey levels and their geometry (cheap, in order). Levels: cascaded area
  // resizing by scale_factor (AreaResize, float); with the default sqrt(2), level l >= 2 is
  // cv::pyrDown of level l - 2 instead (exact factor 2, cheaper still).
  const bool sqrt2 = std::abs(options.scale_factor * options.scale_factor - 2.0) < 1e-6;
  std::vector<cv::Mat> levels;
  for (int l = 0; l < options.num_levels; ++l) {
    cv::Mat level_grey;
    if (l == 0) {
      level_grey = gray;
    } else if (sqrt2 && l >= 2) {
      cv::pyrDown(levels[l - 2], level_grey);
    } else {
      const cv::Mat& prev = levels[l - 1];
      const cv::Size size(static_cast<int>(std::lround(prev.cols / options.scale_factor)),
                          static_cast<int>(std::lround(prev.rows / options.scale_factor)));
      thread_local std::vector<cv::Mat> resized;  // Scratch per level.
      if (static_cast<int>(resized.size()) <= l) resized.resize(l + 1);
      AreaResize(prev, size, &resized[l]);
      level_grey = resized[l];  // This thread's scratch: only read until DetectHarris returns.
    }
    if (level_grey.cols < 4 * options.border || level_grey.rows < 4 * options.border) break;
    levels.push_back(level_grey);
    // Compose the level -> level-0 affine map. Area resizing with ratio r maps pixel
    // centres as u_src = r (u + 0.5) - 0.5; cv::pyrDown as u_src = 2 u (its kernel is centred on
    // the even source pixels).
    PyramidLevel level;
    if (l > 0) {
      const bool pyr = sqrt2 && l >= 2;
      const PyramidLevel& src = result.pyramid[pyr ? l - 2 : l - 1];
      const cv::Mat& src_grey = levels[pyr ? l - 2 : l - 1];
      const double rx = pyr ? 2.0 : static_cast<double>(src_grey.cols) / level_grey.cols;
      const double ry = pyr ? 2.0 : static_cast<double>(src_grey.rows) / level_grey.rows;
      const double bx = pyr ? 0.0 : 0.5 * rx - 0.5, by = pyr ? 0.0 : 0.5 * ry - 0.5;
      level.scale_x = src.scale_x * rx;
      level.scale_y = src.scale_y * ry;
      level.offset_x = src.scale_x * bx + src.offset_x;
      level.offset_y = src.scale_y * by + src.offset_y;
    }
    result.pyramid.push_back(std::move(level));
  }

  // 2. Per level: smoothing and detection. With a helper thread, level 0 (about two thirds of
  // the work) here and the coarser levels there; each level's points are kept apart and joined
  // in level order, so the result is the same as one after the other, bit for bit.
  const int num_levels = static_cast<int>(levels.size());
  std::vector<std::vector<InterestPoint>> level_points(num_levels);
  const auto detect_levels = [&](int first, int last) {
    // 8-bit or float in, float out: the separable filter converts while it smooths.
    const cv::Mat kernel_d =
        cv::getGaussianKernel(KernelSide(options.sigma_d), options.sigma_d, CV_32F);
    for (int l = first; l < last; ++l) {
      PyramidLevel& level = result.pyramid[l];
      level.smoothed = RecycledImage(levels[l].size());
      cv::sepFilter2D(levels[l], level.smoothed, CV_32F, kernel_d, kernel_d, cv::Point(-1, -1),
                      0.0, cv::BORDER_REFLECT_101);
      DetectLevel(level.smoothed, level, l, options, &level_points[l]);
    }
  };
  if (helper != nullptr && num_levels > 1) {
    helper->Start([&] { detect_levels(1, num_levels); });
    detect_levels(0, 1);
    helper->Wait();
  } else {
    detect_levels(0, num_levels);
  }
  for (std::vector<InterestPoint>& points : level_points) {
    result.points.insert(result.points.end(), points.begin(), points.end());
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

  // 3. Descriptors (each row independent of the others: halves on the two threads).
  const int n = options.patch_size * options.patch_size;
  const int num_points = static_cast<int>(result.points.size());
  result.descriptors.create(num_points, n, CV_32F);
  const auto describe = [&](int first, int last) {
    for (int i = first; i < last; ++i) {
      const InterestPoint& p = result.points[i];
      SamplePatch(result, p.uv, p.orientation, p.scale, result.descriptors.ptr<float>(i));
    }
  };
  if (helper != nullptr && num_points > 1) {
    helper->Start([&] { describe(num_points / 2, num_points); });
    describe(0, num_points / 2);
    helper->Wait();
  } else {
    describe(0, num_points);
  }
  return result;
}

}  // namespace dala
