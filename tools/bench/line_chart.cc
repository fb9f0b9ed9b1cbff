#include "tools/bench/line_chart.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "core/eval/chart_drawing.h"

namespace dala::bench {
namespace {

const cv::Scalar kText(40, 40, 40);
const cv::Scalar kGrid(228, 228, 228);
const cv::Scalar kAxis(90, 90, 90);

// Distinct colours (BGR), a Tableau-like palette.
cv::Scalar SeriesColour(size_t i) {
  static const cv::Scalar kPalette[] = {
      {180, 119, 31}, {14, 127, 255},  {44, 160, 44},   {40, 39, 214},  {189, 103, 148},
      {75, 86, 140},  {194, 119, 227}, {127, 127, 127}, {34, 189, 188}, {207, 190, 23}};
  return kPalette[i % (sizeof(kPalette) / sizeof(kPalette[0]))];
}

using chart::NiceStep;
using chart::TextSize;

void Text(cv::Mat* img, const std::string& text, cv::Point at, double scale,
          const cv::Scalar& colour = kText, int thickness = 1) {
  chart::PutText(img, text, at, scale, colour, thickness);
}

int LegendTextWidth(const std::vector<ChartSeries>& series) {
  int w = 0;
  for (const ChartSeries& s : series) w = std::max(w, TextSize(s.name, 0.45).width);
  return w;
}

// The points of a series in the plot area's pixels, x16 for cv's sub-pixel shift of 4 bits.
template <typename ToPixel>
std::vector<cv::Point> SeriesPixels(const ChartSeries& s, const ToPixel& px, const cv::Rect& area) {
  std::vector<cv::Point> pts;
  for (size_t i = 0; i < s.x.size() && i < s.y.size(); ++i) {
    if (!std::isfinite(s.x[i]) || !std::isfinite(s.y[i])) continue;
    const cv::Point2d p = px(s.x[i], s.y[i]) - cv::Point2d(area.x, area.y);
    pts.emplace_back(static_cast<int>(std::lround(p.x * 16)),
                     static_cast<int>(std::lround(p.y * 16)));
  }
  return pts;
}

void DrawSeries(const std::vector<cv::Point>& pts, ChartStyle style, const cv::Scalar& colour,
                cv::Mat* plot) {
  if (style == ChartStyle::kPoints || pts.size() == 1) {
    for (const cv::Point& p : pts) cv::circle(*plot, p, 4 * 16, colour, -1, cv::LINE_AA, 4);
  } else if (style == ChartStyle::kSegments) {
    for (size_t i = 0; i + 1 < pts.size(); i += 2) {
      cv::line(*plot, pts[i], pts[i + 1], colour, 2, cv::LINE_AA, 4);
    }
  } else if (pts.size() > 1) {
    cv::polylines(*plot, pts, false, colour, 2, cv::LINE_AA, 4);
  }
}

}  // namespace

cv::Mat RenderLineChart(const std::vector<ChartSeries>& series, const LineChartOptions& options) {
  cv::Mat img(options.height, options.width, CV_8UC3, cv::Scalar::all(255));
  const int legend_w = options.legend_outside && !series.empty() ? LegendTextWidth(series) + 56 : 0;
  const cv::Rect area(78, 40, options.width - 78 - 20 - legend_w, options.height - 40 - 58);

  double x0 = std::numeric_limits<double>::max(), x1 = -x0, y0 = x0, y1 = -x0;
  for (const ChartSeries& s : series) {
    for (size_t i = 0; i < s.x.size() && i < s.y.size(); ++i) {
      if (!std::isfinite(s.x[i]) || !std::isfinite(s.y[i])) continue;
      x0 = std::min(x0, s.x[i]);
      x1 = std::max(x1, s.x[i]);
      y0 = std::min(y0, s.y[i]);
      y1 = std::max(y1, s.y[i]);
    }
  }
  Text(&img, options.title, {area.x, 26}, 0.6, kText, 1);
  const bool has_data = x0 <= x1;
  if (!has_data) {
    x0 = 0, x1 = 1, y0 = 0, y1 = 1;
  }
  if (!options.x_categories.empty()) {
    x0 = -0.5;
    x1 = static_cast<double>(options.x_categories.size()) - 0.5;
  }
  if (options.y_from_zero && y0 > 0) y0 = 0;
  if (x1 - x0 < 1e-12) x1 = x0 + 1;
  if (y1 - y0 < 1e-12) y1 = y0 + (std::abs(y0) > 0 ? std::abs(y0) * 0.1 : 1.0);
  y1 += 0.05 * (y1 - y0);  // Headroom so that the maximum does not touch the frame.

  const auto px = [&](double x, double y) {
    return cv::Point2d(area.x + (x - x0) / (x1 - x0) * area.width,
                       area.y + area.height - (y - y0) / (y1 - y0) * area.height);
  };
  // Grid and ticks.
  const double xs = NiceStep(x1 - x0, 8), ys = NiceStep(y1 - y0, 5);
  for (size_t i = 0; i < options.x_categories.size(); ++i) {
    const int x = static_cast<int>(std::lround(px(static_cast<double>(i), y0).x));
    cv::line(img, {x, area.y}, {x, area.y + area.height}, kGrid, 1);
    const std::string& t = options.x_categories[i];
    Text(&img, t, {x - TextSize(t, 0.42).width / 2, area.y + area.height + 18}, 0.42);
  }
  for (double v = std::ceil(x0 / xs) * xs; options.x_categories.empty() && v <= x1 + 1e-9 * xs;
       v += xs) {
    const int x = static_cast<int>(std::lround(px(v, y0).x));
    cv::line(img, {x, area.y}, {x, area.y + area.height}, kGrid, 1);
    const std::string t = chart::TickLabel(v, xs);
    Text(&img, t, {x - TextSize(t, 0.42).width / 2, area.y + area.height + 18}, 0.42);
  }
  for (double v = std::ceil(y0 / ys) * ys; v <= y1 + 1e-9 * ys; v += ys) {
    const int y = static_cast<int>(std::lround(px(x0, v).y));
    cv::line(img, {area.x, y}, {area.x + area.width, y}, kGrid, 1);
    const std::string t = chart::TickLabel(v, ys);
    Text(&img, t, {area.x - 8 - TextSize(t, 0.42).width, y + 5}, 0.42);
  }
  cv::rectangle(img, area, kAxis, 1);
  // Axis labels: x centred below, y rotated along the left edge.
  Text(&img, options.x_label,
       {area.x + area.width / 2 - TextSize(options.x_label, 0.48).width / 2, options.height - 12},
       0.48);
  {
    const cv::Size size = TextSize(options.y_label, 0.48);
    cv::Mat patch(size.height + 10, size.width + 4, CV_8UC3, cv::Scalar::all(255));
    Text(&patch, options.y_label, {2, size.height + 3}, 0.48);
    cv::Mat rotated;
    cv::rotate(patch, rotated, cv::ROTATE_90_COUNTERCLOCKWISE);
    const cv::Rect roi(4, area.y + area.height / 2 - rotated.rows / 2, rotated.cols, rotated.rows);
    if ((roi & cv::Rect(0, 0, img.cols, img.rows)) == roi) rotated.copyTo(img(roi));
  }
  // Series, clipped to the plot area.
  cv::Mat plot = img(area);
  for (size_t k = 0; k < series.size(); ++k) {
    DrawSeries(SeriesPixels(series[k], px, area), series[k].style,
               series[k].colour.value_or(SeriesColour(k)), &plot);
  }
  if (!has_data) {
    Text(&img, "no data", {area.x + area.width / 2 - 30, area.y + area.height / 2}, 0.6);
  }
  // Legend in the top-right corner of the plot area, on a white box.
  if (!series.empty()) {
    const int w = LegendTextWidth(series);
    const int row = 20;
    const int left =
        options.legend_outside ? area.x + area.width + 8 : area.x + area.width - w - 48;
    const cv::Rect box(left, area.y + 6, w + 42, row * static_cast<int>(series.size()) + 8);
    cv::rectangle(img, box, cv::Scalar::all(255), -1);
    cv::rectangle(img, box, kAxis, 1);
    for (size_t k = 0; k < series.size(); ++k) {
      const int y = box.y + 14 + row * static_cast<int>(k);
      const cv::Scalar colour = series[k].colour.value_or(SeriesColour(k));
      if (series[k].style == ChartStyle::kPoints) {
        cv::circle(img, {box.x + 17, y - 4}, 4, colour, -1, cv::LINE_AA);
      } else {
        cv::line(img, {box.x + 6, y - 4}, {box.x + 28, y - 4}, colour, 3, cv::LINE_AA);
      }
      Text(&img, series[k].name, {box.x + 34, y + 1}, 0.45);
    }
  }

  return img;
}


void DrawLineChart(const std::vector<ChartSeries>& series, const LineChartOptions& options,
                   const std::string& png_path) {
  chart::WritePng(RenderLineChart(series, options), png_path);
}

void DrawStackedLineCharts(const std::vector<StackedChart>& charts, const std::string& png_path) {
  std::vector<cv::Mat> images;
  int width = 0;
  for (const StackedChart& c : charts) {
    images.push_back(RenderLineChart(c.series, c.options));
    width = std::max(width, images.back().cols);
  }
  for (cv::Mat& img : images) {  // Same width for vconcat: pad on the right with white.
    if (img.cols < width) {
      cv::copyMakeBorder(img, img, 0, 0, 0, width - img.cols, cv::BORDER_CONSTANT,
                         cv::Scalar::all(255));
    }
  }
  cv::Mat stacked;
  if (images.empty()) {
    stacked =
        cv::Mat(LineChartOptions().height, LineChartOptions().width, CV_8UC3, cv::Scalar::all(255));
  } else {
    cv::vconcat(images, stacked);
  }
  chart::WritePng(stacked, png_path);
}

}  // namespace dala::bench
