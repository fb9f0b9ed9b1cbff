#include "core/eval/chart_drawing.h"

#include <cmath>
#include <cstdio>
#include <vector>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "core/error.h"
#include "core/io/atomic_file.h"

namespace dala::chart {
namespace {
constexpr int kFont = cv::FONT_HERSHEY_SIMPLEX;
}  // namespace

double NiceStep(double range, int target) {
  if (!(range > 0.0) || !std::isfinite(range)) return 1.0;
  const double raw = range / target;
  const double magnitude = std::pow(10.0, std::floor(std::log10(raw)));
  const double r = raw / magnitude;
  return (r < 1.5 ? 1.0 : r < 3.5 ? 2.0 : r < 7.5 ? 5.0 : 10.0) * magnitude;
}

std::string TickLabel(double v, double step) {
  const int decimals = step >= 1.0 ? 0 : static_cast<int>(std::ceil(-std::log10(step) - 1e-9));
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.*f", decimals, std::abs(v) < step * 1e-6 ? 0.0 : v);
  return buf;
}

cv::Size TextSize(const std::string& text, double scale, int thickness) {
  int baseline = 0;
  return cv::getTextSize(text, kFont, scale, thickness, &baseline);
}

void PutText(cv::Mat* img, const std::string& text, cv::Point origin, double scale,
             const cv::Scalar& colour, int thickness) {
  cv::putText(*img, text, origin, kFont, scale, colour, thickness, cv::LINE_AA);
}

void WritePng(const cv::Mat& img, const std::string& path) {
  std::vector<uchar> png;
  if (!cv::imencode(".png", img, png)) throw Error() << path << ": cannot encode the image as PNG";
  WriteFileAtomically(path, [&](std::ostream& os) {
    os.write(reinterpret_cast<const char*>(png.data()), static_cast<std::streamsize>(png.size()));
  });
}

}  // namespace dala::chart
