// Diagnosis: an analysis's evidence matched against a unit type's failure
// modes (docs/DIAGNOSIS.md). Pure functions: report, unit type, modes and
// fleet counts in; ranked hypotheses and modules out. No database here.
//
// Evidence. For each identified parameter p with a nominal value v₀ and
// tolerance T in the unit type:
//   positive quantities (σ, τ, ARW, VRW):  x = ln(v/v₀),  s_m = se/v          ("log_ratio")
//   the rest (effects, nominally 0):       x = (v − v₀)/T, s_m = se/T          ("tolerance")
// For each identifiable effect candidate (absent from the model): its
// estimate the same way when the unit type has a tolerance for it, else its
// standard score x = estimate/se, s_m = 0 ("z"). An absent, identifiable,
// non-significant candidate is evidence that the effect is not there: its
// estimate near 0 with its standard error counts against modes predicting it.
// Healthy units scatter with s_h: `healthy_tolerance_sd`, a fraction of
// ln(1 + T/v₀) on the log scale, `healthy_z_sd` for standard scores.
//
// A drift's σ and τ identified together are one bivariate term: their
// measurement errors correlate (ρ, the report's log_correlation), and every
// hypothesis's density of the two is jointly Gaussian with the measurement
// covariance added (kb/src/joint_evidence.h, docs/DIAGNOSIS.md). Each drift's
// distance from nominal, d² = xᵀ(diag(s_h²) + M)⁻¹x, is tested as χ² on its
// degrees of freedom (2 for a pair, 1 for σ alone), Holm-adjusted over the
// unit's drifts; the result is the drift's `significant` and its line.
//
// Likelihood of the evidence under a hypothesis (products over terms):
//   healthy  every term  N(x; 0, s_h² + s_m²)
//   unknown  every term  (1 − ε) N(x; 0, s_h² + s_m²) + ε Cauchy(x; 0, √(b² + s_m²))
//   mode m   its signature's terms as below; a term on a sensor axis the
//            signature reads ("gyro.x") as under `unknown` (a fault's knock-on
//            effects), every other term (1 − ε₀) N + ε₀ Cauchy, ε₀ the share of
//            terms healthy units put off nominal (`incidental_contamination`)
// A signature term with expected change μ, spread s and direction d:
//   single term or family of independent terms, per term j:
//     q · avg_{sign ∈ d} N(x_j; sign·μ, s² + s_h,j² + s_m,j²) + (1 − q) N(x_j; 0, s_h,j² + s_m,j²)
//     (q = `fraction` of the family's terms expected to move; 1 for single terms)
//   family moving together (`common`): one shared shift,
//     avg_{sign ∈ d} N_k(x; sign·μ·1, s² 11ᵀ + diag(s_h,j² + s_m,j²))
//     (Sherman–Morrison for the inverse and the determinant).
//
// Prior (a Gamma–Poisson rate per mode, Bayesian Data Analysis 3rd ed., §2.6):
//   λ_m = (n_m + r_m H₀)/(T_fleet + H₀)   n_m confirmed failures of m in the fleet,
//                                         T_fleet its operating hours, r_m the expert rate,
//                                         H₀ the expert pseudo-exposure
//   h = max(unit's operating hours since its previous analysis, minimum exposure)
//   P(healthy) = (1 − u) e^{−Λh},  P(m) = (1 − u)(1 − e^{−Λh}) λ_m/Λ,  P(unknown) = u,  Λ = Σλ_m
// Posterior ∝ prior × likelihood; a module's probability is the sum over its modes.
// A report without evidence: healthy when its verdict is GOOD, else unknown.
//
// Refinement of a signature term by confirmed cases (normal model with a
// conjugate prior, Bayesian Data Analysis 3rd ed., §3.3; the expert's (μ₀, s₀)
// weighs as κ₀ pseudo-cases): with the cases' oriented values c_1..c_n,
//   μ = (κ₀μ₀ + n c̄)/(κ₀ + n)
//   s² = (κ₀ s₀² + Σ(c_i − c̄)² + κ₀ n (c̄ − μ₀)²/(κ₀ + n)) / (κ₀ + n)
#pragma once

#include <absl/status/statusor.h>

#include <cstdint>
#include <map>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "insdiag/engine/monitor/monitoring.h"
#include "insdiag/kb/knowledge.h"

namespace insdiag::kb {

// What the diagnosis reads of an analysis report
// (proto/insdiag/v1/analyses.proto, AnalysisReport): its verdict, the
// parameters it identified, the effect candidates it tested and the effects
// the discovery loop added.
struct IdentifiedFinding {
  std::string name;  // "gyro_bias_gm.x.sigma"
  double value = 0.0;
  double std_error = 0.0;
  std::string unit;
  std::string method;  // how it was identified: "ACF", "ALLAN", "FILTER", "ML", "STATIC"
  // Identified together with `jointly_with`: the correlation of the two
  // estimates' errors on the log scale.
  std::string jointly_with;
  std::optional<double> log_correlation;
};

struct CandidateFinding {
  std::string name;
  double estimate = 0.0;
  double std_error = 0.0;
  std::string unit;
  double statistic = 0.0;
  int degrees_of_freedom = 0;
  double p_value = 0.0;
  double p_value_holm = 0.0;
  std::string source;  // engine/candidate_source.h's names
  bool identifiable = false;
  bool not_tested = false;
  std::optional<double> onset_s;
  double onset_std_s = 0.0;
};

struct LoopStep {
  int step = 0;
  std::string effect;  // added at this step
  double estimate = 0.0;
  double std_error = 0.0;
  std::string unit;
  double p_value = 0.0;  // Holm-adjusted
};

// The analysis set the unit type's nominal model aside for the run's own
// Allan fit (its UNIT_TYPE_SET_ASIDE decision): the channel whose Allan
// deviation departs from the nominal model, and how far.
struct UnitTypeSetAside {
  std::string channel;  // "gyro_x"
  double tau_s = 0.0;
  double ratio = 0.0;   // the run's Allan deviation over the nominal model's
};

struct ReportFindings {
  std::optional<engine::Verdict> verdict;  // absent: the report states none
  std::optional<UnitTypeSetAside> unit_type_set_aside;
  std::vector<IdentifiedFinding> identified;
  std::vector<CandidateFinding> candidates;
  std::vector<std::string> model_effects;  // the effects of the model that made the report
  std::vector<LoopStep> discovery;
};

// One observed quantity of the evidence.
struct EvidenceTerm {
  std::string name;  // "gyro_bias_gm.x.sigma", "gyro_scale_factor.y", "acc_bias_rw.z"
  Scale scale = Scale::kTolerance;
  double x = 0.0;               // observed change, in scale units
  double measurement_sd = 0.0;  // its standard error, in scale units
  double healthy_sd = 1.0;      // the spread of healthy units, in scale units
  bool significant = false;     // effect candidates: Holm-adjusted p below the level
  double tolerance_units = 0.0; // (v − v₀)/T, for the lines
  std::string line;             // human-readable
  // A trend term (unit_history.h): the parameter whose slope over the unit's
  // own runs x is the standard score of. Empty for every other term.
  std::string trend_of;
  // A term measured together with another (a drift's σ with its τ): the
  // other's name, and the correlation of the two measurement errors; the
  // pair is weighed jointly (kb/src/joint_evidence.h). Empty for a term
  // measured alone.
  std::string jointly_with;
  double measurement_correlation = 0.0;
};

struct Evidence {
  std::vector<EvidenceTerm> terms;
  std::optional<engine::Verdict> verdict;
  std::vector<std::string> notes;
};

// The evidence of one report against the unit type's nominal values.
Evidence EvidenceFromReport(const ReportFindings& report, const UnitType& unit_type,
                            const DiagnosisSettings& settings);

// What the prior needs from the fleet and the unit.
struct PriorInputs {
  double exposure_hours = 0.0;        // the unit's hours since its previous analysis (or all its hours)
  double fleet_exposure_hours = 0.0;  // operating hours of the unit type's fleet
  std::map<std::string, std::int64_t> confirmed_failures;  // by failure mode name
};

// Ranks the hypotheses and modules. `modes` are the unit type's failure
// modes (current signatures). The result's candidates[] (modules, healthy,
// unknown) and hypotheses[] are sorted, most probable first; analysis and
// unit are left for the caller.
Diagnosis Diagnose(const Evidence& evidence, std::span<const FailureMode> modes,
                   const DiagnosisSettings& settings, const PriorInputs& prior);

// Whether signature parameter `pattern` covers evidence term `name`: the
// same name, or for a family "f.*" a term "f.<one part>".
bool SignatureCovers(const std::string& pattern, const std::string& name);

// What a diagnosis says in one line: 1 − P(healthy), and the most probable
// module that is not `healthy` (nullptr when there is none).
struct DiagnosisHeadline {
  double fault_probability = 0.0;
  const Candidate* top = nullptr;
};
DiagnosisHeadline HeadlineOf(const Diagnosis& diagnosis);

// The prior rate λ_m per hour of one mode (see above).
double ModeRatePerHour(const FailureMode& mode, std::int64_t confirmed_failures, double fleet_exposure_hours,
                       const DiagnosisSettings& settings);

// The oriented value of one signature term in a confirmed case's evidence
// (UP: x, DOWN: −x, EITHER: |x|; families: the mean over their terms), or
// nullopt when the evidence does not measure it.
std::optional<double> CaseValue(const Signature& term, const Evidence& evidence);

// The term with change and spread refined by the confirmed cases' values
// (expert values kept in expert_change / expert_spread).
Signature RefineSignature(const Signature& term, std::span<const double> case_values,
                          const DiagnosisSettings& settings);

}  // namespace insdiag::kb
