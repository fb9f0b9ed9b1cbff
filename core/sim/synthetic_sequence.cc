#include "core/sim/synthetic_sequence.h"

#include <glog/logging.h>

#include <algorithm>
#include <cmath>
#include <sstream>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "core/error.h"
#include "core/sim/random.h"
#include "core/sim/recorded_path.h"

namespace dala::sim {
namespace {

// N(0, 1) by Box-Muller on SimRng (platform-independent).
double Gaussian(SimRng& rng) {
  const double u1 = 1.0 - rng.Uniform();  // (0, 1]
  const double u2 = rng.Uniform();
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2 * M_PI * u2);
}

}  // namespace

bool SimOptions::IsValid(std::string* why) const {
  std::ostringstream os;
  if (path.empty() && FindPreset(preset) == nullptr) {
    os << "unknown preset '" << preset << "'; use one of:";
    for (const auto& p : Presets()) os << " " << p.name;
  } else if (frames < 0) {
    os << "frames must be >= 0 (0 = the preset's default), got " << frames;
  } else if (width < 16 || height < 16 || width > 8192 || height > 8192) {
    os << "image size must be within 16..8192 pixels, got " << width << "x" << height;
  } else if (!(fx > 0) || !(fy > 0)) {
    os << "fx and fy must be > 0, got " << fx << ", " << fy;
  } else if (!(fps > 0) || fps > 10000) {
    os << "fps must be in (0, 10000], got " << fps;
  } else if (stereo && !(baseline > 0)) {
    os << "baseline must be > 0 for stereo, got " << baseline;
  } else if (!(std::abs(right_cx_error_px) <= 10)) {
    os << "right_cx_error_px must be within +-10 pixels, got " << right_cx_error_px;
  } else if (!(noise_sigma >= 0)) {
    os << "noise sigma must be >= 0, got " << noise_sigma;
  } else if (motion_blur && (blur_samples == 1 || blur_samples < 0 || blur_samples > 64)) {
    os << "blur_samples must be 0 (automatic) or in 2..64, got " << blur_samples;
  } else if (motion_blur && !(exposure_fraction > 0 && exposure_fraction <= 1)) {
    os << "exposure_fraction must be in (0, 1], got " << exposure_fraction;
  } else if (!(brightness_change >= 0 && brightness_change < 1)) {
    os << "brightness_change must be in [0, 1), got " << brightness_change;
  } else if (!(odometry_sigma_rot >= 0 && odometry_sigma_trans >= 0 &&
               odometry_sigma_trans_fraction >= 0)) {
    os << "odometry sigmas must be >= 0";
  } else if (lens != "pinhole" && lens != "radtan" && lens != "fisheye") {
    os << "lens must be pinhole, radtan or fisheye, got '" << lens << "'";
  } else if (lens == "radtan" && !lens_coefficients.empty() &&
             lens_coefficients.size() != 4 && lens_coefficients.size() != 5) {
    os << "a radtan lens has 4 or 5 coefficients (k1 k2 p1 p2 [k3]), got "
       << lens_coefficients.size();
  } else if (lens == "fisheye" && !lens_coefficients.empty() && lens_coefficients.size() != 4) {
    os << "a fisheye lens has 4 coefficients (k1 k2 k3 k4), got " << lens_coefficients.size();
  } else if (lens == "pinhole" && !lens_coefficients.empty()) {
    os << "lens coefficients need a lens (radtan or fisheye)";
  } else if (texture_size < 64 || texture_size > 4096 || (texture_size & (texture_size - 1))) {
    os << "texture_size must be a power of two in 64..4096, got " << texture_size;
  } else if (!(texel_density_scale > 0.0 && texel_density_scale <= 16.0)) {
    os << "texel_density_scale must be in (0, 16], got " << texel_density_scale;
  } else {
    return true;
  }
  if (why != nullptr) *why = os.str();
  return false;
}

std::vector<double> SimOptions::LensCoefficients() const {
  std::vector<double> k = lens_coefficients;
  if (k.empty() && lens == "radtan") k = {-0.28, 0.07, 2e-4, 2e-5, 0};
  if (k.empty() && lens == "fisheye") k = {0.02, -0.01, 0.005, -0.001};
  k.resize(5, 0.0);
  return k;
}

std::vector<std::string> PresetNames() {
  std::vector<std::string> names;
  for (const auto& p : Presets()) names.push_back(p.name);
  return names;
}

SyntheticSequence::SyntheticSequence(const SimOptions& options) : options_(options) {
  std::string why;
  if (!options_.IsValid(&why)) throw Error() << "synthetic sequence options: " << why;
  // A recorded path is placed first: it throws on a path that cannot be driven on a street.
  std::vector<StampedPose> placed_path;
  if (!options_.path.empty()) {
    placed_path = PlaceOnStreet(options_.path, options_.path_camera_height);
  }
  const double duration_s = placed_path.empty() ? FindPreset(options_.preset)->duration_s
                                                : SecondsFromNs(placed_path.back().t_ns);
  const int default_frames =
      placed_path.empty() ? std::max(1, static_cast<int>(std::lround(duration_s * options_.fps)))
                          : static_cast<int>(std::floor(duration_s * options_.fps + 1e-6)) + 1;
  frames_ = options_.frames > 0 ? options_.frames : default_frames;
  camera_.width = options_.width;
  camera_.height = options_.height;
  camera_.fx = options_.fx;
  camera_.fy = options_.fy;
  camera_.cx = options_.cx_or_centre();
  camera_.cy = options_.cy_or_centre();
  canvas_ = camera_;
  BuildLens();
  world_ = placed_path.empty()
               ? BuildWorld(options_.preset, options_.seed, options_.texture_size,
                            options_.texel_density_scale)
               : BuildWorldAlongPath(placed_path, options_.seed, options_.texture_size,
                                     options_.texel_density_scale);
  for (int i = 0; i < frames_; ++i) ground_truth_.Add(t_ns(i), T_w_c0(i));
}

Eigen::Matrix3d SyntheticSequence::K() const {
  Eigen::Matrix3d K;
  K << camera_.fx, 0, camera_.cx, 0, camera_.fy, camera_.cy, 0, 0, 1;
  return K;
}

Pose SyntheticSequence::T_c0_c1() const {
  Pose T = Pose::Identity();
  T.translation() = Eigen::Vector3d(options_.baseline, 0, 0);
  return T;
}

int64_t SyntheticSequence::t_ns(size_t i) const {
  return std::llround(static_cast<double>(i) * 1e9 / options_.fps);
}

Pose SyntheticSequence::T_w_c0(size_t i) const {
  return world_.path->T_w_c(static_cast<double>(i) / options_.fps);
}

void SyntheticSequence::BuildLens() {
  if (options_.lens == "pinhole") return;
  const std::vector<double> k = options_.LensCoefficients();
  const cv::Mat K = (cv::Mat_<double>(3, 3) << camera_.fx, 0, camera_.cx, 0, camera_.fy,
                     camera_.cy, 0, 0, 1);
  // Every raw pixel's undistorted normalised coordinates (x, y) = (X/Z, Y/Z).
  std::vector<cv::Point2f> raw;
  raw.reserve(static_cast<size_t>(camera_.width) * camera_.height);
  for (int v = 0; v < camera_.height; ++v) {
    for (int u = 0; u < camera_.width; ++u) raw.emplace_back(u, v);
  }
  std::vector<cv::Point2f> normalised;
  if (options_.lens == "fisheye") {
    cv::fisheye::undistortPoints(raw, normalised, K, cv::Mat(cv::Vec4d(k[0], k[1], k[2], k[3])));
  } else {
    cv::undistortPoints(raw, normalised, K,
                        cv::Mat(std::vector<double>(k.begin(), k.end())).reshape(1, 1),
                        cv::noArray(), cv::noArray(),
                        cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 50,
                                         1e-10));
  }
  // The canvas: same focal lengths, centred, wide enough for every ray plus a margin.
  double max_x = 0, max_y = 0;
  for (const cv::Point2f& p : normalised) {
    max_x = std::max(max_x, std::abs(static_cast<double>(p.x)));
    max_y = std::max(max_y, std::abs(static_cast<double>(p.y)));
  }
  const int half_w = static_cast<int>(std::ceil(max_x * camera_.fx)) + 4;
  const int half_h = static_cast<int>(std::ceil(max_y * camera_.fy)) + 4;
  CHECK_LT(half_w, 8192) << "the lens's field of view is too wide to render through a pinhole";
  CHECK_LT(half_h, 8192) << "the lens's field of view is too wide to render through a pinhole";
  canvas_.width = 2 * half_w + 1;
  canvas_.height = 2 * half_h + 1;
  canvas_.cx = half_w;
  canvas_.cy = half_h;
  lens_map_x_.create(camera_.height, camera_.width, CV_32FC1);
  lens_map_y_.create(camera_.height, camera_.width, CV_32FC1);
  for (int v = 0, i = 0; v < camera_.height; ++v) {
    for (int u = 0; u < camera_.width; ++u, ++i) {
      lens_map_x_.at<float>(v, u) = static_cast<float>(canvas_.fx * normalised[i].x + canvas_.cx);
      lens_map_y_.at<float>(v, u) = static_cast<float>(canvas_.fy * normalised[i].y + canvas_.cy);
    }
  }
}

cv::Mat SyntheticSequence::RenderView(const Pose& T_w_c, cv::Mat* depth) const {
  cv::Mat radiance, image;
  RenderScene(world_.scene, camera_, T_w_c, &radiance, depth);
  radiance.convertTo(image, CV_8UC1);  // Rounds and saturates.
  return image;
}

cv::Mat SyntheticSequence::RenderCamera(size_t i, int cam) const {
  const double t = static_cast<double>(i) / options_.fps;
  const Pose T_c0_c = cam == 0 ? Pose::Identity() : T_c0_c1();
  PinholeCamera camera = canvas_;  // camera_ without a lens.
  if (cam == 1) camera.cx += options_.right_cx_error_px;
  cv::Mat radiance;
  if (options_.motion_blur) {
    const double exposure = options_.exposure_fraction / options_.fps;
    int n = options_.blur_samples;
    if (n == 0) {
      // Image motion over the exposure: rotation angle times the focal length plus the
      // translation's parallax at 4 m (the nearest surfaces a rover sees).
      const Pose d =
          world_.path->T_w_c(t - exposure / 2).inverse() * world_.path->T_w_c(t + exposure / 2);
      const double pixels = std::max(camera_.fx, camera_.fy) *
                            (LogSO3(d.linear()).norm() + d.translation().norm() / 4.0);
      n = std::clamp(static_cast<int>(std::ceil(pixels / 3.0)) + 1, 2, 12);
    }
    cv::Mat sum = cv::Mat::zeros(camera.height, camera.width, CV_32FC1), sample;
    for (int k = 0; k < n; ++k) {
      const double tk = t + exposure * (static_cast<double>(k) / (n - 1) - 0.5);
      RenderScene(world_.scene, camera, world_.path->T_w_c(tk) * T_c0_c, &sample);
      sum += sample;
    }
    radiance = sum * (1.0 / n);
  } else {
    RenderScene(world_.scene, camera, world_.path->T_w_c(t) * T_c0_c, &radiance);
  }
  if (!lens_map_x_.empty()) {
    cv::Mat through_lens;
    cv::remap(radiance, through_lens, lens_map_x_, lens_map_y_, cv::INTER_LINEAR,
              cv::BORDER_REPLICATE);
    radiance = through_lens;
  }
  if (options_.brightness_change > 0) {
    SimRng phase_rng(MixSeed(options_.seed, 77));
    const double phase = phase_rng.Uniform(0, 2 * M_PI);
    const double wave = std::sin(2 * M_PI * t / 6.3 + phase);
    const double gain = 1.0 + options_.brightness_change * wave * (cam == 0 ? 1.0 : 1.02);
    radiance *= gain;
  }
  if (options_.noise_sigma > 0) {
    cv::Mat noise(radiance.size(), CV_32FC1);
    cv::RNG rng(MixSeed(options_.seed, 1000 + i, cam));
    rng.fill(noise, cv::RNG::NORMAL, 0.0, options_.noise_sigma);
    radiance += noise;
  }
  cv::Mat image;
  radiance.convertTo(image, CV_8UC1);
  return image;
}

Frame SyntheticSequence::Render(size_t i) const {
  CHECK_LT(i, size()) << "frame index out of range";
  Frame frame;
  frame.id = FrameId(static_cast<int64_t>(i));
  frame.t_ns = t_ns(i);
  frame.T_w_c0_gt = T_w_c0(i);
  frame.left = RenderCamera(i, 0);
  if (options_.stereo) frame.right = RenderCamera(i, 1);
  return frame;
}

Trajectory NoisyOdometry(const Trajectory& ground_truth, uint64_t seed, double sigma_rot,
                         double sigma_trans, double sigma_trans_fraction) {
  Trajectory odometry;
  if (ground_truth.empty()) return odometry;
  SimRng rng(MixSeed(seed, 555));
  Pose T_w_c = ground_truth.poses[0].T_w_c;
  odometry.Add(ground_truth.poses[0].t_ns, T_w_c);
  for (size_t i = 1; i < ground_truth.size(); ++i) {
    const Pose T_prev_cur = ground_truth.poses[i - 1].T_w_c.inverse() * ground_truth.poses[i].T_w_c;
    const double st = sigma_trans + sigma_trans_fraction * T_prev_cur.translation().norm();
    Vector6d noise;
    for (int k = 0; k < 6; ++k) noise[k] = Gaussian(rng) * (k < 3 ? sigma_rot : st);
    T_w_c = Orthonormalized(T_w_c * T_prev_cur * ExpSE3(noise));
    odometry.Add(ground_truth.poses[i].t_ns, T_w_c);
  }
  return odometry;
}

}  // namespace dala::sim
