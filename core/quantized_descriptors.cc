#include "core/quantized_descriptors.h"

#include <glog/logging.h>

#include <algorithm>
#include <cmath>

namespace dala {

void QuantizeDescriptor(const float* row, int n, int8_t* out) {
  float max_abs = 0.f;
  for (int k = 0; k < n; ++k) max_abs = std::max(max_abs, std::abs(row[k]));
  const float to_int = max_abs > 0.f ? 127.f / max_abs : 0.f;
  for (int k = 0; k < n; ++k) out[k] = static_cast<int8_t>(std::lround(row[k] * to_int));
}

void ExpandDescriptor(const int8_t* q, int n, float* out) {
  double mean = 0.0;
  for (int k = 0; k < n; ++k) mean += q[k];
  mean /= n;
  // Zero mean, unit norm again (m_r / 127 cancels: only the integers matter).
  double norm2 = 0.0;
  for (int k = 0; k < n; ++k) norm2 += (q[k] - mean) * (q[k] - mean);
  const double inv = norm2 > 0.0 ? 1.0 / std::sqrt(norm2) : 0.0;
  for (int k = 0; k < n; ++k) out[k] = static_cast<float>((q[k] - mean) * inv);
}

void QuantizedDescriptors::Append(const float* row) {
  CHECK_GT(cols_, 0) << "QuantizedDescriptors: no row size";
  samples_.resize(samples_.size() + cols_);
  QuantizeDescriptor(row, cols_, samples_.data() + samples_.size() - cols_);
}

void QuantizedDescriptors::AppendQuantized(const int8_t* row) {
  CHECK_GT(cols_, 0) << "QuantizedDescriptors: no row size";
  samples_.insert(samples_.end(), row, row + cols_);
}

void QuantizedDescriptors::AppendRow(const cv::Mat& descriptors, int r) {
  CHECK_EQ(descriptors.type(), CV_32F);
  CHECK_EQ(descriptors.cols, cols_) << "QuantizedDescriptors: rows of another size";
  Append(descriptors.ptr<float>(r));
}

void QuantizedDescriptors::ExpandRow(int r, float* out) const {
  CHECK(r >= 0 && r < rows());
  ExpandDescriptor(samples_.data() + static_cast<size_t>(r) * cols_, cols_, out);
}

cv::Mat QuantizedDescriptors::Expand() const {
  cv::Mat out(rows(), cols_, CV_32F);
  for (int r = 0; r < rows(); ++r) ExpandRow(r, out.ptr<float>(r));
  return out;
}

}  // namespace dala
