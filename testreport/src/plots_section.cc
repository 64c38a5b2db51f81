#include <absl/strings/match.h>
#include <absl/strings/str_cat.h>

#include <cmath>
#include <limits>

#include "sections.h"

namespace insdiag::testreport {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

std::string ChannelUnit(const v1::AnalysisReport& report, const std::string& channel) {
  for (const auto& c : report.channels()) {
    if (c.name() == channel) return c.unit();
  }
  return "";
}

// The residual's envelope as one line: down to each column's minimum and up
// to its maximum, so that a one-epoch spike keeps its full height.
Plot ResidualPlot(const v1::AnalysisReport& report, const v1::ChannelEnvelope& e) {
  const std::string unit = ChannelUnit(report, e.channel());
  Plot plot;
  plot.title = absl::StrCat(e.channel(), ": residual (measured − predicted) and ±3σ");
  plot.x_label = "time [s]";
  plot.y_label = unit.empty() ? "residual" : absl::StrCat("residual [", unit, "]");
  PlotSeries residual{"residual", {}, {}, SeriesColor::kData, false};
  PlotSeries upper{"±3σ", {}, {}, SeriesColor::kBand, true};
  PlotSeries lower{"", {}, {}, SeriesColor::kBand, true};
  for (int i = 0; i < e.t_size(); ++i) {
    const double t = e.t(i);
    residual.x.insert(residual.x.end(), {t, t});
    residual.y.insert(residual.y.end(), {e.residual_min(i), e.residual_max(i)});
    if (i < e.sigma3_max_size()) {
      upper.x.push_back(t), upper.y.push_back(e.sigma3_max(i));
      lower.x.push_back(t), lower.y.push_back(-e.sigma3_max(i));
    }
  }
  plot.series = {std::move(upper), std::move(lower), std::move(residual)};
  for (const auto& f : report.fault_intervals()) {
    if (f.channel() == e.channel()) plot.shaded_x.push_back({f.start_s(), f.end_s()});
  }
  return plot;
}

// The Allan deviations of one sensor's three axes, measured and fitted.
Plot AllanPlot(const v1::AnalysisReport& report, const std::string& sensor) {
  constexpr SeriesColor kAxisColors[] = {SeriesColor::kData, SeriesColor::kSecond, SeriesColor::kThird};
  Plot plot;
  plot.x_label = "averaging time τ [s]";
  plot.log_x = plot.log_y = true;
  int axis = 0;
  std::string unit;
  for (const auto& curve : report.allan()) {
    if (!absl::StartsWith(curve.channel(), sensor + "_")) continue;
    unit = curve.unit();
    const SeriesColor color = kAxisColors[axis++ % 3];
    PlotSeries measured{curve.channel(), {}, {}, color, false};
    PlotSeries fitted{"", {}, {}, color, true};
    for (int i = 0; i < curve.tau_s_size() && i < curve.deviation_size(); ++i) {
      measured.x.push_back(curve.tau_s(i));
      measured.y.push_back(curve.deviation(i) > 0 ? curve.deviation(i) : kNaN);
      if (i < curve.fitted_size()) {
        fitted.x.push_back(curve.tau_s(i));
        fitted.y.push_back(curve.fitted(i) > 0 ? curve.fitted(i) : kNaN);
      }
    }
    plot.series.push_back(std::move(measured));
    if (!fitted.x.empty()) plot.series.push_back(std::move(fitted));
  }
  plot.title = absl::StrCat(sensor == "gyro" ? "Gyroscopes" : "Accelerometers",
                            ": Allan deviation of the static segments (dashed: fitted noise model)");
  plot.y_label = unit.empty() ? "Allan deviation" : absl::StrCat("Allan deviation [", unit, "]");
  return plot;
}

}  // namespace

Section PlotsSection(const v1::AnalysisReport& report, const v1::DisplaySeries& residuals) {
  Section s{"Plots", {}};
  for (const auto& envelope : residuals.channels()) {
    if (envelope.t_size() > 0) s.blocks.push_back(ResidualPlot(report, envelope));
  }
  if (residuals.channels().empty()) {
    s.blocks.push_back(Paragraph{"The analysis stored no residual series to plot."});
  }
  for (const char* sensor : {"gyro", "acc"}) {
    Plot allan = AllanPlot(report, sensor);
    if (!allan.series.empty()) s.blocks.push_back(std::move(allan));
  }
  return s;
}

}  // namespace insdiag::testreport
