#ifndef DALA_TOOLS_BENCH_LINE_CHART_H_
#define DALA_TOOLS_BENCH_LINE_CHART_H_

// A small line chart drawn with OpenCV into a PNG (no plotting library): title, axes with
// 1-2-5 ticks and grid, axis labels, one polyline per series and a legend.

#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace dala::bench {

// How a series is drawn: a polyline; a dot per point (a strip plot); or a segment per pair of
// points (x[0],y[0])-(x[1],y[1]), (x[2],y[2])-(x[3],y[3]), ... (e.g. a median bar per category).
enum class ChartStyle { kLine, kPoints, kSegments };

struct ChartSeries {
  ChartSeries() = default;
  ChartSeries(std::string name, std::vector<double> x, std::vector<double> y,
              ChartStyle style = ChartStyle::kLine)
      : name(std::move(name)), x(std::move(x)), y(std::move(y)), style(style) {}

  std::string name;  // Legend entry.
  std::vector<double> x, y;
  ChartStyle style = ChartStyle::kLine;
  std::optional<cv::Scalar> colour;  // BGR; default: the palette's colour of its position.
};

struct LineChartOptions {
  std::string title;
  std::string x_label;
  std::string y_label;
  int width = 900;   // Pixels.
  int height = 380;  // Pixels.
  // The y axis starts at 0 (errors, times) unless a value is negative.
  bool y_from_zero = true;
  // A categorical x axis: category i is drawn at x = i, labelled with its name, and the axis
  // spans [-0.5, n - 0.5]. Empty: a numeric axis over the data.
  std::vector<std::string> x_categories;
  // The legend to the right of the plot area instead of over its top-right corner (for many
  // entries, or points that would hide under it).
  bool legend_outside = false;
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
