#ifndef DALA_FRONTEND_HARRIS_H_
#define DALA_FRONTEND_HARRIS_H_

// "Precise" Harris interest points (Schmid, Mohr & Bauckhage's evaluation; Lemaire et al. 2007),
// detected on an image pyramid, each with its auto-correlation attributes and a rotation- and
// scale-normalised grey-level patch used by the matcher (frontend/matcher.h).
//
// Per pyramid level l (image I_l, level-0 pixels per level pixel s_l = scale_factor^l):
//   S   = G(sigma_d) * I_l                         smoothed image (also used for the patches)
//   I_x, I_y = central differences of S           = derivatives of a Gaussian of sigma_d
//   M   = G(sigma_i) * [I_x^2  I_xI_y; I_xI_y  I_y^2]   Gaussian-weighted auto-correlation
//   R   = det M - k (trace M)^2                    cornerness; lambda1 >= lambda2 eigenvalues of M
// Points are the 3x3 local maxima of R above max(min_cornerness, relative_threshold * max R),
// refined to sub-pixel precision by the extremum of the quadratic fitted to R on the 3x3
// neighbourhood, and spread over the image by a bucketing grid (at most max_per_cell per cell).
// The orientation is the direction of the Gaussian-weighted (sigma_orientation) mean gradient
// around the point, i.e. the gradient of S smoothed once more: stable at corners, where it is the
// bisector of the corner.
//
// Usage:
//   dala::HarrisOptions options;           // defaults suit 640x480..1241x376 images
//   dala::DetectedImage det = dala::DetectHarris(gray, options);
//   for (const dala::InterestPoint& p : det.points) ... p.uv, p.orientation ...
//
// Thread safety: DetectHarris is re-entrant (it only reads its inputs; its scratch images and
// the pool its pyramid images are recycled from are per thread).

#include <Eigen/Core>
#include <memory>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "frontend/neighbour_cache.h"

namespace dala {

struct InterestPoint {
  Eigen::Vector2d uv = Eigen::Vector2d::Zero();  // Level-0 pixel coordinates (OpenCV centres).
  float cornerness = 0.f;                        // det M - k trace(M)^2 at the detection level.
  float lambda1 = 0.f;                           // Largest eigenvalue of M.
  float lambda2 = 0.f;                           // Smallest eigenvalue of M.
  float orientation = 0.f;  // Dominant gradient direction, radians in (-pi, pi], image axes.
  float scale = 1.f;        // Level-0 pixels per pixel of the detection level.
  int level = 0;            // Pyramid level of detection.
};

struct HarrisOptions {
  double sigma_d = 1.0;              // Derivation scale (level pixels).
  double sigma_i = 2.0;              // Integration scale of the auto-correlation matrix.
  double k = 0.04;                   // Harris constant in det - k trace^2.
  double relative_threshold = 1e-3;  // Keep R > relative_threshold * max R of the level.
  double min_cornerness = 1e-3;      // Absolute floor on R (grey levels 0..255: R ~ contrast^4).
  // Keep lambda2 / lambda1 >= min_eigen_ratio: Harris R > 0 already needs about k (0.04) here,
  // but points on curved edges just above it all look alike once rotation-normalised.
  double min_eigen_ratio = 0.1;
  int num_levels = 4;                // Pyramid levels (1 = no pyramid).
  double scale_factor = 1.41421356;  // Size ratio between consecutive levels (> 1).
  int cell_size = 32;                // Bucketing cell side (level pixels); 0 disables bucketing.
  int max_per_cell = 5;              // Strongest points kept per cell.
  int max_points = 3000;             // Cap on the total number of points (strongest first).
  int border = 8;                    // Points closer than this to the level border are dropped.
  double sigma_orientation = 2.5;    // Gaussian window of the orientation estimate (level px).
  int patch_size = 11;               // Side of the patch descriptor (odd), samples.
  double patch_spacing = 1.5;        // Sample spacing in level pixels at the detection scale.

  bool IsValid(std::string* why) const;
};

// One pyramid level: what detection computed and the matcher reuses.
struct PyramidLevel {
  cv::Mat smoothed;  // CV_32F, G(sigma_d) * I_l.
  // Level pixel (u_l, v_l) is level-0 pixel (scale_x u_l + offset_x, scale_y v_l + offset_y).
  double scale_x = 1.0, scale_y = 1.0;  // Level-0 pixels per level pixel.
  double offset_x = 0.0, offset_y = 0.0;
};

// The detection result for one image, computed once and reused by every match involving it.
struct DetectedImage {
  std::vector<InterestPoint> points;
  // Row r = z-normalised patch of points[r], divided by sqrt(patch_size^2) so that the dot
  // product of two rows is their ZNCC. CV_32F, points.size() x patch_size^2.
  cv::Mat descriptors;
  std::vector<PyramidLevel> pyramid;
  cv::Size image_size;
  int patch_size = 11;
  double patch_spacing = 1.5;
  // The matcher's k-nearest-neighbour lists of `points`, computed on first use (neighbour_cache.h).
  std::shared_ptr<NeighbourCache> neighbour_cache = std::make_shared<NeighbourCache>();
};

class WorkerThread;

// Detects interest points on an 8-bit grey image (CV_8UC1). CHECK-fails on invalid options or an
// image of another type (callers validate at their I/O boundary). With an idle `helper` thread
// the pyramid levels and the descriptors are split between it and the caller (one camera: the
// second core is otherwise idle during detection); the result is the same, bit for bit.
DetectedImage DetectHarris(const cv::Mat& gray, const HarrisOptions& options,
                           WorkerThread* helper = nullptr);

// Samples the normalised patch of `image` centred at level-0 pixel `uv`, rotated by `orientation`
// and of scale `scale` (level-0 pixels per patch unit spacing / patch_spacing), from the pyramid
// level whose scale is closest, bilinearly, z-normalised and divided by sqrt(n) (n samples).
// Writes image.patch_size^2 floats to `out`. Returns false when the patch is flat (no texture).
bool SamplePatch(const DetectedImage& image, const Eigen::Vector2d& uv, double orientation,
                 double scale, float* out);

}  // namespace dala

#endif  // DALA_FRONTEND_HARRIS_H_
