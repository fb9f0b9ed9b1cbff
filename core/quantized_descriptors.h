#ifndef DALA_CORE_QUANTIZED_DESCRIPTORS_H_
#define DALA_CORE_QUANTIZED_DESCRIPTORS_H_

// Patch descriptors (frontend/harris.h: z-normalised rows whose dot product is their ZNCC)
// stored at 8 bits per sample, for what lives as long as the run: the place-recognition
// database and the keyframe records of the map file. Four times smaller than the CV_32F rows
// (121 samples: 121 bytes instead of 484), which were most of the memory a long run grows by
// (docs/results.md, "Memory over a long drive").
//
// Row r is stored as q_r[k] = round(127 x_r[k] / m_r) with m_r = max_k |x_r[k]|. Expanding
// removes the mean of q_r and divides by its norm, so an expanded row is again a unit, zero-mean
// vector (the factor m_r / 127 cancels and is not kept) and dot products stay ZNCCs.
// The rounding error is at most m_r / 254 per sample (uniform: m_r / (127 sqrt(12)) rms); on
// real patches (121 samples of rms 1/11) it moved no ZNCC of 45,000 pairs by more than 2.4e-3,
// and the matcher found the same correct matches under rotation and scale
// (tests/frontend/quantized_descriptors_test.cc).

#include <cstddef>
#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>

namespace dala {

// One row of n samples to 8 bits (see above), and back (zero mean, unit norm).
void QuantizeDescriptor(const float* row, int n, int8_t* out);
void ExpandDescriptor(const int8_t* q, int n, float* out);

// Rows of one size, stored at 8 bits.
class QuantizedDescriptors {
 public:
  QuantizedDescriptors() = default;
  // Empty, rows of `cols` samples.
  explicit QuantizedDescriptors(int cols) : cols_(cols) {}

  // Appends one row of cols() floats.
  void Append(const float* row);
  // Appends one row already quantised (cols() samples, as QuantizeDescriptor writes them).
  void AppendQuantized(const int8_t* row);
  // Appends row `r` of a CV_32F matrix with cols() columns (CHECKed).
  void AppendRow(const cv::Mat& descriptors, int r);

  // Row r expanded (see the file comment) into `out` (cols() floats).
  void ExpandRow(int r, float* out) const;
  // Every row expanded: CV_32F, rows() x cols().
  cv::Mat Expand() const;

  int rows() const { return cols_ > 0 ? static_cast<int>(samples_.size() / cols_) : 0; }
  int cols() const { return cols_; }
  // Heap bytes held (what the memory accounting of a long run counts).
  size_t bytes() const { return samples_.capacity(); }
  void shrink_to_fit() { samples_.shrink_to_fit(); }

 private:
  int cols_ = 0;
  std::vector<int8_t> samples_;  // rows() x cols_, row-major.
};

}  // namespace dala

#endif  // DALA_CORE_QUANTIZED_DESCRIPTORS_H_
