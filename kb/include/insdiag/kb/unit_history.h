// A unit's history: the statistics of one identified parameter across the
// unit's runs (one point per run), and what a significant trend contributes
// to the diagnosis. Pure functions; no database here.
//
// Points (t_i [day], y_i, s_i = the run's standard error), i = 1..n.
//
// Run-to-run repeatability: the sample standard deviation
//   ȳ = Σ y_i / n,   s = √(Σ (y_i − ȳ)² / (n − 1))
// and its two-sided confidence interval at level 1 − α from
// (n − 1) s²/σ² ~ χ²(n − 1) (NIST/SEMATECH e-Handbook of Statistical
// Methods, §1.3.5.8, "Chi-Square Test for the Standard Deviation"):
//   [ s √((n − 1)/χ²_{1−α/2}(n − 1)),  s √((n − 1)/χ²_{α/2}(n − 1)) ].
//
// Turn-on-to-turn-on repeatability of a turn-on bias (a constant the unit
// takes anew at each power-up, shared/spec/effects.md): the standard
// deviation τ of the bias itself between turn-ons, each run's bias measured
// with its error s_i. The random-effects moment estimate of DerSimonian &
// Laird (Controlled Clinical Trials 7 (1986) 177–188, eq. 3–4):
//   w_i = 1/s_i²,  ȳ_w = Σ w_i y_i / Σ w_i,  Q = Σ w_i (y_i − ȳ_w)²
//   τ² = max(0, (Q − (n − 1)) / (Σ w_i − Σ w_i² / Σ w_i)).
//
// Trend: the straight line y = a + b t by weighted least squares, w_i = 1/s_i²
// (Bevington & Robinson, Data Reduction and Error Analysis for the Physical
// Sciences, 3rd ed., §6.4, eq. 6.12 and 6.21–6.22):
//   S = Σw, S_t = Σ w t, S_y = Σ w y, S_tt = Σ w t², S_ty = Σ w t y,
//   Δ = S S_tt − S_t²,  b = (S S_ty − S_t S_y)/Δ,  a = (S_tt S_y − S_t S_ty)/Δ,
//   σ_b² = S/Δ,
//   χ² = Σ w_i (y_i − a − b t_i)² on ν = n − 2 degrees of freedom;
// the scatter exceeds what the SEs explain when P(χ²(ν) ≥ χ²) < α. Then σ_b
// is multiplied by the Birge ratio R = √(χ²/ν) (the scale factor of the
// Review of Particle Physics, "Introduction", §5.2.2 "Unconstrained
// averaging") and the slope's test uses Student's t on ν degrees of freedom;
// otherwise z = b/σ_b against N(0, 1). Without every s_i (some run gave no
// SE), ordinary least squares (w_i = 1) with σ_b² = (χ²/ν) S/Δ and Student's t.
// Student's t tail: P(|T| > t) = I_{ν/(ν+t²)}(ν/2, 1/2) (Abramowitz & Stegun
// 26.7.1 with 26.5.27), the regularised incomplete beta function by its
// continued fraction (DLMF 8.17.22) evaluated by the modified Lentz method.
//
// Trend as evidence of a failure mode (docs/DIAGNOSIS.md): the slope's
// standard score z, with the same two-sided p-value as the slope's test
// (z = sign(b) Φ⁻¹(1 − p/2)), enters the diagnosis when its Holm-adjusted
// p-value over the unit's parameters is below the significance level.
#pragma once

#include <absl/time/time.h>

#include <optional>
#include <span>
#include <string>
#include <vector>

#include "insdiag/kb/diagnosis.h"

namespace insdiag::kb {

struct HistoryPoint {
  double days = 0.0;       // since the first point
  double value = 0.0;
  double std_error = 0.0;  // ≤ 0 or not finite: unknown
};

struct HistoryOptions {
  double confidence = 0.95;  // of the repeatability interval; α = 1 − confidence for the scatter test
  bool Validate() const { return confidence > 0.0 && confidence < 1.0; }
};

// The weighted straight line through a parameter's points (the trend above).
// Not fitted (below 3 points, or all on one day): every field zero.
struct TrendFit {
  bool fitted = false;
  // true: weights 1/SE²; false: equal weights (some run gave no SE).
  bool weighted = false;
  double slope_per_day = 0.0;
  // Its standard error, multiplied by the Birge ratio when the scatter
  // exceeds what the SEs explain.
  double slope_std_error_per_day = 0.0;
  double intercept = 0.0;  // the value at day 0
  double p_value = 0.0;    // two-sided, slope = 0
  double chi_square = 0.0;  // of the residuals, in units of the SEs
  int degrees_of_freedom = 0;
  double scatter_p_value = 0.0;  // P(χ² ≥ chi_square) when the SEs explain the scatter
  bool excess_scatter = false;   // scatter_p_value below 1 − confidence
  // max(1, √(χ²/dof)) on weighted fits with excess scatter; 1 on other fitted ones.
  double birge_ratio = 0.0;
};

// One parameter's statistics across its points; the values in the
// parameter's unit.
struct ParameterStatistics {
  int count = 0;
  double mean = 0.0;
  // Run-to-run repeatability: the sample standard deviation and its χ²
  // interval (count ≥ 2; zero otherwise).
  double run_to_run_sd = 0.0;
  double run_to_run_sd_low = 0.0;
  double run_to_run_sd_high = 0.0;
  double rms_std_error = 0.0;  // of the points' standard errors (unknown ones as 0)
  // DerSimonian–Laird τ: only for a turn-on bias with every SE known (count ≥ 2).
  std::optional<double> turn_on_to_turn_on_sd;
  std::optional<TrendFit> trend;  // none without points
};

// One run's value of a parameter: the run's latest succeeded analysis.
struct RunParameterPoint {
  std::string run;       // runs/{run}
  std::string analysis;  // analyses/{analysis}
  absl::Time test_time;  // the run's test time, else its upload
  double days = 0.0;     // since the unit's first point of this parameter
  double value = 0.0;
  double std_error = 0.0;  // 0 when the analysis gave none
};

// A parameter over a unit's runs.
struct ParameterHistory {
  std::string name;  // "gyro_turn_on_bias.x", "gyro_bias_gm.x.sigma"
  std::string unit;  // of value and std_error, e.g. "rad/s"
  bool turn_on_bias = false;  // IsTurnOnBias(name)
  std::vector<RunParameterPoint> points;  // oldest first
  ParameterStatistics statistics;
};

// Every statistic of one parameter's points (in time order or not).
// `turn_on_bias` asks for the turn-on-to-turn-on repeatability.
ParameterStatistics ParameterStatisticsOf(std::span<const HistoryPoint> points, bool turn_on_bias,
                                          const HistoryOptions& options);

// The weighted straight line alone (count ≥ 3; `fitted` false otherwise).
TrendFit FitTrend(std::span<const HistoryPoint> points, const HistoryOptions& options);

// Whether `parameter` ("gyro_turn_on_bias.x") is a turn-on bias: a constant
// catalogue effect on the sensor's own output (regressor 1).
bool IsTurnOnBias(const std::string& parameter);

// P(|T| > t) for Student's t on `dof` degrees of freedom.
double StudentTwoSidedPValue(double t, double dof);

// The evidence a unit's own history gives a diagnosis: one term on the
// standard-score scale per parameter whose trend is significant (Holm over
// the parameters with a fitted trend, at settings.significance_level()),
// named "<parameter>.trend" with `trend_of` set. None when the settings
// have no trend model (trend_z_spread ≤ 0).
std::vector<EvidenceTerm> TrendEvidence(std::span<const ParameterHistory> parameters,
                                        const DiagnosisSettings& settings);

}  // namespace insdiag::kb
