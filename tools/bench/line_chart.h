#ifndef DALA_TOOLS_BENCH_LINE_CHART_H_
#define DALA_TOOLS_BENCH_LINE_CHART_H_

// A small line chart drawn with OpenCV into a PNG (no plotting library): title, axes with
// 1-2-5 ticks and grid, axis labels, one polyline per series and a legend.

#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace dala::bench {

struct ChartSeries {
  std::string name;  // Legend entry.
  std::vector<double> x, y;
};

struct LineChartOptions {
  std::string title;
  std::string x_label;
  std::string y_label;
  int width = 900;   // Pixels.
  int height = 380;  // Pixels.
  // The y axis starts at 0 (errors, times) unless a value is negative.
  bool y_from_zero = true;
};

// Draws the chart and writes it atomically to `png_path`; throws dala::Error naming the path
// when it cannot be written. Series with no points are listed in the legend only; an empty chart
// says "no data".
void DrawLineChart(const std::vector<ChartSeries>& series, const LineChartOptions& options,
                   const std::string& png_path);

// The chart as an image (CV_8UC3, options.width x options.height).
cv::Mat RenderLineChart(const std::vector<ChartSeries>& series, const LineChartOptions& options);

// Several charts one above the other in one PNG (written atomically), e.g. quantities of
// different units against the same x.
struct StackedChart {
  std::vector<ChartSeries> series;
  LineChartOptions options;
};
void DrawStackedLineCharts(const std::vector<StackedChart>& charts, const std::string& png_path);

}  // namespace dala::bench

#endif  // DALA_TOOLS_BENCH_LINE_CHART_H_
