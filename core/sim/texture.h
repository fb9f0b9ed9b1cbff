#ifndef DALA_CORE_SIM_TEXTURE_H_
#define DALA_CORE_SIM_TEXTURE_H_

// Procedural grey-level textures for the synthetic world, and their anti-aliased sampling.

#include <cstdint>
#include <opencv2/core.hpp>
#include <vector>

namespace dala::sim {

// A square, power-of-two, tileable (wrap-around) grey texture with a mip pyramid. Texel
// coordinates follow the OpenCV pixel convention at level 0 (centre of texel (0,0) at (0,0));
// level l halves the resolution (cv::pyrDown), so level-0 coordinate x maps to x / 2^l there.
// Sampling wraps around, so any real coordinate is valid. Thread-safe after construction.
class Texture {
 public:
  // base: CV_8UC1 or CV_32FC1, square, power-of-two side >= 8; values in [0, 255].
  explicit Texture(const cv::Mat& base);

  int size() const { return size_; }
  int levels() const { return static_cast<int>(levels_.size()); }
  const cv::Mat& level(int l) const { return levels_[l]; }

  // Trilinear sample at level-0 texel coordinates (x, y) and level of detail `lod`
  // (log2 of texels per pixel; <= 0 means magnification: bilinear at level 0).
  float Sample(double x, double y, float lod) const;

 private:
  float SampleLevel(int l, double x, double y) const;

  int size_ = 0;
  std::vector<cv::Mat> levels_;  // CV_32FC1, continuous.
};

// The kind of texture a scene uses.
enum class TextureStyle {
  kRich,  // Layered random polygons, blobs and strokes of varied grey at four scales.
  kWeak,  // Smooth shading with a few sparse, low-contrast shapes.
};

// A deterministic texture from `seed` (same seed and style -> bit-identical texels). The
// texture tiles seamlessly (shapes wrap around the borders). side: power of two.
cv::Mat MakeTextureImage(uint64_t seed, TextureStyle style, int side = 1024);

}  // namespace dala::sim

#endif  // DALA_CORE_SIM_TEXTURE_H_
