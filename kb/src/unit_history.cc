#include "insdiag/kb/unit_history.h"

#include <absl/strings/str_cat.h>
#include <absl/strings/str_format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "insdiag/engine/model/parameter_key.h"
#include "insdiag/engine/stats/distributions.h"

namespace insdiag::kb {
namespace {

namespace stats = engine::stats;

// Residuals this many units in the last place of the largest value are rounding.
constexpr double kRoundingUlps = 64.0;

bool KnownError(double se) { return std::isfinite(se) && se > 0.0; }

bool AllErrorsKnown(std::span<const HistoryPoint> points) {
  return std::all_of(points.begin(), points.end(), [](const HistoryPoint& p) { return KnownError(p.std_error); });
}

// The continued fraction of I_x(a, b) (DLMF 8.17.22), 1/(1 + d₁/(1 + d₂/(1 + …))),
// by the modified Lentz method; it converges fast for x < (a + 1)/(a + b + 2).
double BetaContinuedFraction(double a, double b, double x) {
  constexpr double kTiny = 1e-300;
  constexpr double kTolerance = 1e-15;
  constexpr int kMaxTerms = 1000;
  double f = 1.0, c = 1.0, d = 0.0;
  for (int j = 1; j <= kMaxTerms; ++j) {
    const double m = static_cast<double>(j / 2);
    const double coefficient = j % 2 == 0 ? m * (b - m) * x / ((a + 2.0 * m - 1.0) * (a + 2.0 * m))
                                          : -(a + m) * (a + b + m) * x / ((a + 2.0 * m) * (a + 2.0 * m + 1.0));
    d = 1.0 + coefficient * d;
    d = 1.0 / (std::abs(d) < kTiny ? kTiny : d);
    c = 1.0 + coefficient / c;
    if (std::abs(c) < kTiny) c = kTiny;
    f *= c * d;
    if (std::abs(c * d - 1.0) < kTolerance) break;
  }
  return 1.0 / f;
}

// The regularised incomplete beta function I_x(a, b).
double RegularizedBeta(double a, double b, double x) {
  if (x <= 0.0) return 0.0;
  if (x >= 1.0) return 1.0;
  // Past the fraction's fast region, I_x(a, b) = 1 − I_{1−x}(b, a).
  if (x > (a + 1.0) / (a + b + 2.0)) return 1.0 - RegularizedBeta(b, a, 1.0 - x);
  const double log_front =
      a * std::log(x) + b * std::log1p(-x) - std::log(a) - (std::lgamma(a) + std::lgamma(b) - std::lgamma(a + b));
  return std::exp(log_front) * BetaContinuedFraction(a, b, x);
}

double TwoSidedNormalPValue(double z) { return 2.0 * stats::NormalCdf(-std::abs(z)); }

}  // namespace

double StudentTwoSidedPValue(double t, double dof) {
  if (!std::isfinite(t)) return 0.0;
  return RegularizedBeta(0.5 * dof, 0.5, dof / (dof + t * t));
}

bool IsTurnOnBias(const std::string& parameter) {
  const std::optional<engine::ParameterKey> key = engine::ParseParameterKey(parameter);
  const engine::EffectFamily* family = key ? key->effect_family : nullptr;
  return family != nullptr && family->kind == engine::EffectKind::kConstant &&
         family->regressor == engine::Regressor::kOne;
}

TrendFit FitTrend(std::span<const HistoryPoint> points, const HistoryOptions& options) {
  TrendFit fit;
  const std::size_t n = points.size();
  if (n < 3) return fit;
  const bool weighted = AllErrorsKnown(points);
  double s = 0.0, s_t = 0.0, s_y = 0.0, s_tt = 0.0, s_ty = 0.0;
  for (const auto& p : points) {
    const double w = weighted ? 1.0 / (p.std_error * p.std_error) : 1.0;
    s += w;
    s_t += w * p.days;
    s_y += w * p.value;
    s_tt += w * p.days * p.days;
    s_ty += w * p.days * p.value;
  }
  const double delta = s * s_tt - s_t * s_t;
  // All points on one day: no slope to speak of.
  if (!(delta > 0.0) || !std::isfinite(delta)) return fit;
  const double slope = (s * s_ty - s_t * s_y) / delta;
  const double intercept = (s_tt * s_y - s_t * s_ty) / delta;
  double chi_square = 0.0;
  for (const auto& p : points) {
    const double w = weighted ? 1.0 / (p.std_error * p.std_error) : 1.0;
    const double r = p.value - intercept - slope * p.days;
    chi_square += w * r * r;
  }
  const double dof = static_cast<double>(n - 2);
  const double alpha = 1.0 - options.confidence;
  fit.fitted = true;
  fit.weighted = weighted;
  fit.slope_per_day = slope;
  fit.intercept = intercept;
  fit.chi_square = chi_square;
  fit.degrees_of_freedom = static_cast<int>(n - 2);
  fit.birge_ratio = 1.0;
  double se = std::sqrt(s / delta);
  if (weighted) {
    fit.scatter_p_value = stats::ChiSquareSurvival(chi_square, dof);
    fit.excess_scatter = fit.scatter_p_value < alpha;
    if (fit.excess_scatter) fit.birge_ratio = std::max(1.0, std::sqrt(chi_square / dof));
    se *= fit.birge_ratio;
  } else {
    // Equal weights: the residuals alone tell the points' scatter — but not
    // below the values' rounding, or a parameter reported at one value in
    // every run would show a "trend" of rounding error with no error at all.
    double largest = 0.0;
    for (const auto& p : points) largest = std::max(largest, std::abs(p.value));
    const double rounding = kRoundingUlps * std::numeric_limits<double>::epsilon() * largest;
    fit.scatter_p_value = 1.0;
    se *= std::max(std::sqrt(chi_square / dof), rounding);
  }
  fit.slope_std_error_per_day = se;
  const bool student = !weighted || fit.excess_scatter;
  if (se > 0.0) {
    fit.p_value = student ? StudentTwoSidedPValue(slope / se, dof) : TwoSidedNormalPValue(slope / se);
  } else {
    fit.p_value = slope == 0.0 ? 1.0 : 0.0;  // points exactly on a line
  }
  return fit;
}

ParameterStatistics ParameterStatisticsOf(std::span<const HistoryPoint> points, bool turn_on_bias,
                                          const HistoryOptions& options) {
  ParameterStatistics out;
  const std::size_t n = points.size();
  out.count = static_cast<int>(n);
  if (n == 0) return out;
  double sum = 0.0, se_square_sum = 0.0;
  for (const auto& p : points) {
    sum += p.value;
    se_square_sum += KnownError(p.std_error) ? p.std_error * p.std_error : 0.0;
  }
  const double mean = sum / static_cast<double>(n);
  out.mean = mean;
  out.rms_std_error = std::sqrt(se_square_sum / static_cast<double>(n));
  out.trend = FitTrend(points, options);
  if (n < 2) return out;
  double squares = 0.0;
  for (const auto& p : points) squares += (p.value - mean) * (p.value - mean);
  const double dof = static_cast<double>(n - 1);
  const double sd = std::sqrt(squares / dof);
  const double alpha = 1.0 - options.confidence;
  out.run_to_run_sd = sd;
  out.run_to_run_sd_low = sd * std::sqrt(dof / stats::ChiSquareQuantile(1.0 - 0.5 * alpha, dof));
  out.run_to_run_sd_high = sd * std::sqrt(dof / stats::ChiSquareQuantile(0.5 * alpha, dof));
  if (turn_on_bias && AllErrorsKnown(points)) {
    double sw = 0.0, sw2 = 0.0, swy = 0.0;
    for (const auto& p : points) {
      const double w = 1.0 / (p.std_error * p.std_error);
      sw += w;
      sw2 += w * w;
      swy += w * p.value;
    }
    const double weighted_mean = swy / sw;
    double q = 0.0;
    for (const auto& p : points) {
      const double r = p.value - weighted_mean;
      q += r * r / (p.std_error * p.std_error);
    }
    out.turn_on_to_turn_on_sd = std::sqrt(std::max(0.0, (q - dof) / (sw - sw2 / sw)));
  }
  return out;
}

std::vector<EvidenceTerm> TrendEvidence(std::span<const ParameterHistory> parameters,
                                        const DiagnosisSettings& settings) {
  std::vector<EvidenceTerm> out;
  if (settings.trend_z_spread <= 0.0) return out;
  std::vector<const ParameterHistory*> fitted;
  std::vector<double> p_values;
  for (const auto& p : parameters) {
    if (!p.statistics.trend.has_value() || !p.statistics.trend->fitted) continue;
    fitted.push_back(&p);
    p_values.push_back(p.statistics.trend->p_value);
  }
  std::vector<double> holm(p_values.size());
  stats::HolmAdjust(p_values, holm);
  for (std::size_t i = 0; i < fitted.size(); ++i) {
    if (holm[i] >= settings.significance_level) continue;
    const ParameterHistory& p = *fitted[i];
    const TrendFit& trend = *p.statistics.trend;
    EvidenceTerm t;
    t.name = absl::StrCat(p.name, ".trend");
    t.trend_of = p.name;
    t.scale = Scale::kZ;
    // The standard score of the slope's own two-sided p-value (normal or
    // Student's t), so that a healthy unit's scatters as N(0, 1).
    t.x = std::copysign(-stats::NormalQuantile(0.5 * std::clamp(trend.p_value, 1e-300, 1.0)),
                        trend.slope_per_day);
    t.measurement_sd = 0.0;
    t.healthy_sd = settings.healthy_z_sd;
    t.significant = true;
    const std::string unit = p.unit.empty() ? "" : absl::StrCat(" ", p.unit);
    t.line = absl::StrFormat("%s: trend over the unit's %d runs %+.3g ± %.2g%s per day (z = %.1f, Holm p = %.2g), "
                             "significant",
                             p.name, p.statistics.count, trend.slope_per_day,
                             trend.slope_std_error_per_day, unit, t.x, holm[i]);
    out.push_back(std::move(t));
  }
  return out;
}

}  // namespace insdiag::kb
