#include "core/eval/plot.h"

#include <glog/logging.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "core/eval/chart_drawing.h"

namespace dala {
namespace {

const cv::Scalar kBlack(0, 0, 0);
const cv::Scalar kGrid(225, 225, 225);
const cv::Scalar kAxisText(40, 40, 40);
const cv::Scalar kGtColour(60, 60, 60);      // Dark grey.
const cv::Scalar kEstColour(180, 105, 30);   // Blue (BGR).
const cv::Scalar kErrorColour(40, 40, 200);  // Red (BGR).
constexpr int kShift = 4;  // Sub-pixel drawing: coordinates in 1/16 pixel.
constexpr double kSubPixel = 16.0;

cv::Point ToFixed(const cv::Point2d& p) {
  return {static_cast<int>(std::lround(p.x * kSubPixel)),
          static_cast<int>(std::lround(p.y * kSubPixel))};
}

using chart::NiceStep;
using chart::PutText;
using chart::TextSize;
using chart::TickLabel;

// Text rotated by 90 degrees (reading upwards), centred at `centre`.
void PutVerticalText(cv::Mat* img, const std::string& text, cv::Point centre, double scale,
                     const cv::Scalar& colour) {
  const cv::Size size = TextSize(text, scale);
  cv::Mat patch(size.height + 10, size.width + 4, img->type(), cv::Scalar::all(255));
  PutText(&patch, text, {2, size.height + 3}, scale, colour);
  cv::Mat rotated;
  cv::rotate(patch, rotated, cv::ROTATE_90_COUNTERCLOCKWISE);
  const cv::Rect roi(centre.x - rotated.cols / 2, centre.y - rotated.rows / 2, rotated.cols,
                     rotated.rows);
  if ((roi & cv::Rect(0, 0, img->cols, img->rows)) == roi) rotated.copyTo((*img)(roi));
}

// A data -> pixel mapping for one plot area, with ticks, grid and axis labels.
struct Axes {
  cv::Rect area;  // Pixel rectangle of the plot area.
  double x0 = 0, x1 = 1, y0 = 0, y1 = 1;

  cv::Point2d Map(double x, double y) const {
    return {area.x + (x - x0) / (x1 - x0) * area.width,
            area.y + area.height - (y - y0) / (y1 - y0) * area.height};
  }

  void Draw(cv::Mat* img, const std::string& x_label, const std::string& y_label,
            const std::string& title) const {
    const double sx = NiceStep(x1 - x0, std::max(3, area.width / 110));
    const double sy = NiceStep(y1 - y0, std::max(3, area.height / 55));
    const double label_scale = 0.45;
    for (double x = std::ceil(x0 / sx) * sx; x <= x1 + 1e-9 * sx; x += sx) {
      const cv::Point2d p = Map(x, y0);
      cv::line(*img, ToFixed({p.x, static_cast<double>(area.y)}), ToFixed(p), kGrid, 1, cv::LINE_AA,
               kShift);
      cv::line(*img, ToFixed(p), ToFixed({p.x, p.y + 6}), kBlack, 1, cv::LINE_AA, kShift);
      const std::string label = TickLabel(x, sx);
      const cv::Size s = TextSize(label, label_scale);
      PutText(img, label, {static_cast<int>(p.x) - s.width / 2, static_cast<int>(p.y) + 22},
              label_scale, kAxisText);
    }
    int widest = 0;
    for (double y = std::ceil(y0 / sy) * sy; y <= y1 + 1e-9 * sy; y += sy) {
      const cv::Point2d p = Map(x0, y);
      cv::line(*img, ToFixed(p), ToFixed({static_cast<double>(area.x + area.width), p.y}), kGrid, 1,
               cv::LINE_AA, kShift);
      cv::line(*img, ToFixed({p.x - 6, p.y}), ToFixed(p), kBlack, 1, cv::LINE_AA, kShift);
      const std::string label = TickLabel(y, sy);
      const cv::Size s = TextSize(label, label_scale);
      widest = std::max(widest, s.width);
      PutText(img, label,
              {static_cast<int>(p.x) - 10 - s.width, static_cast<int>(p.y) + s.height / 2},
              label_scale, kAxisText);
    }
    cv::rectangle(*img, area, kBlack, 1);
    const double axis_scale = 0.55;
    const cv::Size xs = TextSize(x_label, axis_scale);
    PutText(img, x_label, {area.x + area.width / 2 - xs.width / 2, area.y + area.height + 48},
            axis_scale, kBlack);
    PutVerticalText(img, y_label, {area.x - 24 - widest, area.y + area.height / 2}, axis_scale,
                    kBlack);
    const cv::Size ts = TextSize(title, 0.62);
    PutText(img, title, {area.x + area.width / 2 - ts.width / 2, area.y - 14}, 0.62, kBlack);
  }

  void Polyline(cv::Mat* img, const std::vector<cv::Point2d>& data, const cv::Scalar& colour,
                int thickness) const {
    std::vector<cv::Point> pts;
    pts.reserve(data.size());
    for (const cv::Point2d& d : data) pts.push_back(ToFixed(Map(d.x, d.y)));
    const std::vector<std::vector<cv::Point>> polys = {pts};
    cv::polylines(*img, polys, false, colour, thickness, cv::LINE_AA, kShift);
  }
};

void DashedHorizontal(cv::Mat* img, const Axes& axes, double y, const cv::Scalar& colour) {
  const cv::Point2d a = axes.Map(axes.x0, y);
  const double x_end = axes.area.x + axes.area.width;
  for (double x = a.x; x < x_end; x += 14) {
    cv::line(*img, ToFixed({x, a.y}), ToFixed({std::min(x + 8, x_end), a.y}), colour, 1,
             cv::LINE_AA, kShift);
  }
}

void Legend(cv::Mat* img, const cv::Point& top_right,
            const std::vector<std::pair<std::string, cv::Scalar>>& entries) {
  const double scale = 0.5;
  int width = 0;
  for (const auto& e : entries) width = std::max(width, TextSize(e.first, scale).width);
  const int row = 24;
  const cv::Rect box(top_right.x - width - 62, top_right.y, width + 52,
                     static_cast<int>(entries.size()) * row + 12);
  cv::rectangle(*img, box, cv::Scalar::all(255), cv::FILLED);
  cv::rectangle(*img, box, cv::Scalar::all(170), 1);
  for (size_t i = 0; i < entries.size(); ++i) {
    const int y = box.y + 18 + static_cast<int>(i) * row;
    cv::line(*img, {box.x + 8, y - 4}, {box.x + 36, y - 4}, entries[i].second, 2, cv::LINE_AA);
    PutText(img, entries[i].first, {box.x + 44, y}, scale, kBlack);
  }
}

const char* AxisName(int axis) { return axis == 0 ? "x" : (axis == 1 ? "y" : "z"); }

}  // namespace

void PlotEvaluation(const Trajectory& gt, const Trajectory& aligned_est, const EvalResult& result,
                    const std::string& png_path) {
  CHECK(result.ok) << "PlotEvaluation needs a successful evaluation";
  CHECK(!gt.empty());
  const int width = 1200;
  const int top_height = 820;
  const int bottom_height = 380;
  cv::Mat img(top_height + bottom_height, width, CV_8UC3, cv::Scalar::all(255));

  // Top view: the two axes along which the ground truth spreads most.
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::max());
  Eigen::Vector3d hi = -lo;
  for (const StampedPose& p : gt.poses) {
    lo = lo.cwiseMin(p.T_w_c.translation());
    hi = hi.cwiseMax(p.T_w_c.translation());
  }
  const Eigen::Vector3d gt_extent = hi - lo;
  for (const StampedPose& p : aligned_est.poses) {
    lo = lo.cwiseMin(p.T_w_c.translation());
    hi = hi.cwiseMax(p.T_w_c.translation());
  }
  int axes_idx[3] = {0, 1, 2};
  std::sort(axes_idx, axes_idx + 3, [&](int a, int b) { return gt_extent[a] > gt_extent[b]; });
  int ax = std::min(axes_idx[0], axes_idx[1]);
  int ay = std::max(axes_idx[0], axes_idx[1]);

  Axes top;
  top.area = cv::Rect(110, 60, width - 150, top_height - 150);
  // Equal aspect: one metre is the same number of pixels on both axes.
  const double margin = 0.04;
  double rx = std::max(hi[ax] - lo[ax], 1e-3);
  double ry = std::max(hi[ay] - lo[ay], 1e-3);
  const double ppm =
      std::min(top.area.width / (rx * (1 + 2 * margin)), top.area.height / (ry * (1 + 2 * margin)));
  const double cx = 0.5 * (lo[ax] + hi[ax]);
  const double cy = 0.5 * (lo[ay] + hi[ay]);
  top.x0 = cx - 0.5 * top.area.width / ppm;
  top.x1 = cx + 0.5 * top.area.width / ppm;
  top.y0 = cy - 0.5 * top.area.height / ppm;
  top.y1 = cy + 0.5 * top.area.height / ppm;
  char title[200];
  std::snprintf(
      title, sizeof(title), "Top view (%s-%s), %s%s, ATE RMSE %.4g m", AxisName(ax), AxisName(ay),
      result.options.alignment == AlignmentType::kNone
          ? "no alignment"
          : (std::string(AlignmentTypeName(result.options.alignment)) + " alignment").c_str(),
      result.options.alignment == AlignmentType::kSim3
          ? (" (scale " + std::to_string(result.alignment.scale).substr(0, 6) + ")").c_str()
          : "",
      result.ate.translation.rmse);
  top.Draw(&img, std::string(AxisName(ax)) + " [m]", std::string(AxisName(ay)) + " [m]", title);
  const auto project = [&](const Trajectory& t) {
    std::vector<cv::Point2d> pts;
    for (const StampedPose& p : t.poses)
      pts.emplace_back(p.T_w_c.translation()[ax], p.T_w_c.translation()[ay]);
    return pts;
  };
  const std::vector<cv::Point2d> gt_pts = project(gt);
  const std::vector<cv::Point2d> est_pts = project(aligned_est);
  top.Polyline(&img, gt_pts, kGtColour, 2);
  if (!est_pts.empty()) top.Polyline(&img, est_pts, kEstColour, 2);
  // Start markers: a ring in each trajectory's colour on its first pose.
  const auto start_marker = [&](const cv::Point2d& p, const cv::Scalar& colour) {
    const cv::Point c = ToFixed(top.Map(p.x, p.y));
    cv::circle(img, c, 8 * 16, cv::Scalar::all(255), cv::FILLED, cv::LINE_AA, kShift);
    cv::circle(img, c, 8 * 16, colour, 3, cv::LINE_AA, kShift);
  };
  start_marker(gt_pts.front(), kGtColour);
  if (!est_pts.empty()) start_marker(est_pts.front(), kEstColour);
  Legend(
      &img, {top.area.x + top.area.width - 8, top.area.y + 8},
      {{"ground truth", kGtColour},
       {result.options.alignment == AlignmentType::kNone
            ? std::string("estimate (not aligned)")
            : std::string("estimate (") + AlignmentTypeName(result.options.alignment) + " aligned)",
        kEstColour}});
  {
    const std::string note = "rings: start";
    PutText(&img, note, {top.area.x + 8, top.area.y + top.area.height - 10}, 0.45,
            cv::Scalar::all(110));
  }

  // ATE along the path.
  Axes bottom;
  bottom.area = cv::Rect(110, top_height + 40, width - 150, bottom_height - 110);
  const std::vector<double>& errors = result.ate.translation_errors;
  const bool by_distance = result.gt_path_length_m > 0.0;
  std::vector<cv::Point2d> series;
  for (size_t i = 0; i < errors.size(); ++i) {
    series.emplace_back(by_distance ? result.pair_distance_m[i] : static_cast<double>(i),
                        errors[i]);
  }
  bottom.x0 = 0.0;
  bottom.x1 = std::max(series.back().x, 1e-3);
  bottom.y0 = 0.0;
  bottom.y1 = std::max(result.ate.translation.max * 1.1, 1e-6);
  std::snprintf(
      title, sizeof(title),
      "ATE translation error per pair (%zu pairs): mean %.4g m, median %.4g m, max %.4g m",
      errors.size(), result.ate.translation.mean, result.ate.translation.median,
      result.ate.translation.max);
  bottom.Draw(&img, by_distance ? "distance travelled along the ground truth [m]" : "pair index",
              "ATE [m]", title);
  DashedHorizontal(&img, bottom, result.ate.translation.rmse, kBlack);
  bottom.Polyline(&img, series, kErrorColour, 1);
  char rmse_label[64];
  std::snprintf(rmse_label, sizeof(rmse_label), "RMSE %.4g m (dashed)",
                result.ate.translation.rmse);
  Legend(&img, {bottom.area.x + bottom.area.width - 8, bottom.area.y + 8},
         {{"ATE", kErrorColour}, {rmse_label, kBlack}});

  chart::WritePng(img, png_path);
}

}  // namespace dala
