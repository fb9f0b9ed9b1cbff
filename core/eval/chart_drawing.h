#ifndef DALA_CORE_EVAL_CHART_DRAWING_H_
#define DALA_CORE_EVAL_CHART_DRAWING_H_

// What every PNG chart dala draws shares (core/eval/plot.h: the trajectory plots of `dala eval`
// and `dala run`; tools/bench/line_chart.h: the per-frame and bench charts): axis ticks at
// round numbers, anti-aliased Hershey text, and the atomic PNG write.

#include <string>

#include <opencv2/core.hpp>

namespace dala::chart {

// A step of 1, 2 or 5 x 10^k giving about `target` intervals over `range` (1 when the range is
// empty or not finite).
double NiceStep(double range, int target);
// `v` with as many decimals as `step` needs ("0" for a value within 1e-6 steps of zero).
std::string TickLabel(double v, double step);

cv::Size TextSize(const std::string& text, double scale, int thickness = 1);
// Text whose baseline starts at `origin`.
void PutText(cv::Mat* img, const std::string& text, cv::Point origin, double scale,
             const cv::Scalar& colour, int thickness = 1);

// Encodes `img` as PNG and writes it atomically (core/io/atomic_file.h). dala::Error naming the
// path when it cannot be encoded or written.
void WritePng(const cv::Mat& img, const std::string& path);

}  // namespace dala::chart

#endif  // DALA_CORE_EVAL_CHART_DRAWING_H_
