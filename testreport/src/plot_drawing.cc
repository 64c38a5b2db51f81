#include "plot_drawing.h"

#include <absl/strings/str_format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "insdiag/testreport/pdf_writer.h"

namespace insdiag::testreport {
namespace {

// The plot's frame inside its box: room for the title and legend above,
// the y tick labels to the left, the x tick labels and label below.
constexpr double kFrameLeft = 54.0;
constexpr double kFrameRight = 8.0;
constexpr double kFrameTop = 30.0;
constexpr double kFrameBottom = 26.0;
constexpr double kTitleSize = 8.5;
constexpr double kLabelSize = 7.0;
constexpr int kTargetTicks = 5;

const Rgb kInk{0.1, 0.1, 0.1};
const Rgb kGrid{0.88, 0.88, 0.88};
const Rgb kShade{1.0, 0.86, 0.86};

// One axis: its range, linear or in decades, and where a value lands
// between two pixel positions.
struct Axis {
  double lo = 0.0;
  double hi = 1.0;
  bool log = false;
  std::vector<double> ticks;

  double Position(double v, double p_lo, double p_hi) const {
    const double u = log ? (std::log10(v) - lo) / (hi - lo) : (v - lo) / (hi - lo);
    return p_lo + u * (p_hi - p_lo);
  }
  double TickValue(double t) const { return log ? std::pow(10.0, t) : t; }
};

// 1, 2 or 5 times a power of ten: steps a reader counts in.
double NiceStep(double span) {
  const double raw = span / kTargetTicks;
  const double decade = std::pow(10.0, std::floor(std::log10(raw)));
  for (const double m : {1.0, 2.0, 5.0}) {
    if (m * decade >= raw) return m * decade;
  }
  return 10.0 * decade;
}

Axis MakeAxis(const std::vector<double>& values, bool log) {
  double lo = std::numeric_limits<double>::infinity();
  double hi = -lo;
  for (const double v : values) {
    if (!std::isfinite(v) || (log && v <= 0)) continue;
    const double u = log ? std::log10(v) : v;
    lo = std::min(lo, u), hi = std::max(hi, u);
  }
  Axis axis;
  axis.log = log;
  if (!std::isfinite(lo)) return axis;  // nothing to show: the default [0, 1]
  if (log) {
    // A value a rounding error off a decade (τ = 0.09999… s) keeps that decade as the axis's end.
    constexpr double kDecadeSlack = 1e-6;
    axis.lo = std::floor(lo + kDecadeSlack), axis.hi = std::max(std::ceil(hi - kDecadeSlack), axis.lo + 1.0);
    const double step = std::ceil((axis.hi - axis.lo) / (kTargetTicks + 1));
    for (double t = axis.lo; t <= axis.hi + 1e-9; t += step) axis.ticks.push_back(t);
    return axis;
  }
  if (hi - lo <= 0) {
    const double half = lo == 0 ? 1.0 : std::abs(lo) * 0.1;
    lo -= half, hi += half;
  }
  const double step = NiceStep(hi - lo);
  axis.lo = std::floor(lo / step) * step, axis.hi = std::ceil(hi / step) * step;
  for (double t = axis.lo; t <= axis.hi + step * 1e-6; t += step) {
    axis.ticks.push_back(std::abs(t) < step * 1e-9 ? 0.0 : t);
  }
  return axis;
}

std::string TickLabel(const Axis& axis, double t) {
  if (axis.log) return absl::StrFormat("1e%d", static_cast<int>(std::lround(t)));
  // Whole numbers as they are (a run's seconds: 3000, not 3e+03).
  if (std::abs(t) < 1e7 && t == std::round(t)) return absl::StrFormat("%.0f", t);
  return absl::StrFormat("%.3g", t);
}

void DrawLegend(const Plot& plot, double width, Canvas& canvas) {
  double x = width - kFrameRight;
  const double y = kFrameTop - 8.0;
  for (auto it = plot.series.rbegin(); it != plot.series.rend(); ++it) {
    if (it->label.empty()) continue;
    canvas.Text(x, y + 2.5, kLabelSize, Anchor::kEnd, false, it->label, kInk);
    x -= TextWidth(it->label, kLabelSize, false) + 3.0;
    canvas.Polyline({{x - 14.0, y}, {x, y}}, 1.2, ColorOf(it->color), it->dashed);
    x -= 24.0;
  }
}

void DrawAxes(const Axis& ax, const Axis& ay, const Plot& plot, double left, double right, double top, double bottom,
              Canvas& canvas) {
  for (const double t : ax.ticks) {
    const double x = ax.Position(ax.TickValue(t), left, right);
    canvas.Polyline({{x, top}, {x, bottom}}, 0.4, kGrid, false);
    canvas.Text(x, bottom + 9.0, kLabelSize, Anchor::kMiddle, false, TickLabel(ax, t), kInk);
  }
  for (const double t : ay.ticks) {
    const double y = ay.Position(ay.TickValue(t), bottom, top);
    canvas.Polyline({{left, y}, {right, y}}, 0.4, kGrid, false);
    canvas.Text(left - 3.0, y + 2.5, kLabelSize, Anchor::kEnd, false, TickLabel(ay, t), kInk);
  }
  canvas.Polyline({{left, top}, {right, top}, {right, bottom}, {left, bottom}, {left, top}}, 0.6, kInk, false);
  canvas.Text((left + right) / 2, bottom + 21.0, kLabelSize, Anchor::kMiddle, false, plot.x_label, kInk);
  canvas.Text(0.0, kFrameTop - 5.5, kLabelSize, Anchor::kStart, false, plot.y_label, kInk);
}

// Each series as runs of finite points (a non-finite value breaks the line).
void DrawSeries(const PlotSeries& s, const Axis& ax, const Axis& ay, double left, double right, double top,
                double bottom, Canvas& canvas) {
  std::vector<std::pair<double, double>> run;
  const auto flush = [&] {
    if (run.size() >= 2) canvas.Polyline(run, s.dashed ? 0.8 : 0.9, ColorOf(s.color), s.dashed);
    run.clear();
  };
  for (std::size_t i = 0; i < s.x.size() && i < s.y.size(); ++i) {
    const double x = s.x[i], y = s.y[i];
    const bool drawable = std::isfinite(x) && std::isfinite(y) && (!ax.log || x > 0) && (!ay.log || y > 0);
    if (!drawable) {
      flush();
      continue;
    }
    run.push_back({ax.Position(x, left, right), ay.Position(y, bottom, top)});
  }
  flush();
}

}  // namespace

Rgb ColorOf(SeriesColor color) {
  switch (color) {
    case SeriesColor::kData: return {0.12, 0.32, 0.66};
    case SeriesColor::kBand: return {0.45, 0.45, 0.45};
    case SeriesColor::kFit: return {0.85, 0.45, 0.10};
    case SeriesColor::kSecond: return {0.13, 0.55, 0.25};
    case SeriesColor::kThird: return {0.78, 0.20, 0.20};
  }
  return kInk;
}

double TextWidth(const std::string& text, double size, bool bold) {
  return TextWidthPt(text, bold ? PdfFont::kHelveticaBold : PdfFont::kHelvetica, size);
}

void DrawPlot(const Plot& plot, double width, double height, Canvas& canvas) {
  const double left = kFrameLeft, right = width - kFrameRight;
  const double top = kFrameTop, bottom = height - kFrameBottom;
  std::vector<double> xs, ys;
  for (const auto& s : plot.series) {
    xs.insert(xs.end(), s.x.begin(), s.x.end());
    ys.insert(ys.end(), s.y.begin(), s.y.end());
  }
  const Axis ax = MakeAxis(xs, plot.log_x);
  const Axis ay = MakeAxis(ys, plot.log_y);
  canvas.Text(0.0, kTitleSize + 1.0, kTitleSize, Anchor::kStart, true, plot.title, kInk);
  for (const auto& [from, to] : plot.shaded_x) {
    const double x0 = std::clamp(ax.Position(std::max(from, ax.TickValue(ax.lo)), left, right), left, right);
    const double x1 = std::clamp(ax.Position(std::min(to, ax.TickValue(ax.hi)), left, right), left, right);
    if (to >= from && x1 >= x0) canvas.Rect(x0, top, std::max(x1 - x0, 0.8), bottom - top, kShade);
  }
  DrawAxes(ax, ay, plot, left, right, top, bottom, canvas);
  for (const auto& s : plot.series) DrawSeries(s, ax, ay, left, right, top, bottom, canvas);
  DrawLegend(plot, width, canvas);
}

}  // namespace insdiag::testreport
