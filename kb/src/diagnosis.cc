#include "insdiag/kb/diagnosis.h"

#include <absl/strings/match.h>
#include <absl/strings/str_cat.h>
#include <absl/strings/str_format.h>
#include <absl/strings/str_join.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <set>

#include "densities.h"
#include "evidence_text.h"
#include "insdiag/engine/candidate_source.h"
#include "insdiag/engine/model/effect_catalogue.h"
#include "insdiag/engine/model/parameter_key.h"
#include "insdiag/engine/stats/distributions.h"
#include "joint_evidence.h"

namespace insdiag::kb {
namespace {

using internal::Format;
using internal::LogAddExp;
using internal::LogBroad;
using internal::LogNormalPdf;
using internal::SignedFormat;

constexpr char kHealthy[] = "healthy";
constexpr char kUnknown[] = "unknown";

double HealthyLog(const EvidenceTerm& t) {
  return LogNormalPdf(t.x, 0.0, internal::HealthyVariance(t));
}

// (1 − ε) healthy + ε broad: evidence off, with probability ε, for a reason
// the hypothesis does not name.
double ContaminatedLog(const EvidenceTerm& t, double eps, const DiagnosisSettings& s) {
  if (eps <= 0.0) return HealthyLog(t);
  return LogAddExp(std::log1p(-eps) + HealthyLog(t), std::log(eps) + LogBroad(t, s));
}

// The sensor axis a term reads: "gyro_bias_gm.x.sigma" → "gyro.x"; a
// misalignment "gyro_misalignment.xy" reads into its first (output) axis.
std::string SensorAxisOf(const std::string& term_name) {
  const std::optional<engine::ParameterKey> key = engine::ParseParameterKey(term_name);
  return key ? key->SensorAxis() : "";
}

bool IsFamily(const std::string& parameter) { return absl::EndsWith(parameter, ".*"); }

std::vector<const EvidenceTerm*> Members(const Signature& term, const Evidence& evidence) {
  std::vector<const EvidenceTerm*> out;
  for (const auto& t : evidence.terms) {
    if (t.trend_of.empty() && SignatureCovers(term.parameter, t.name) && t.scale == term.scale) {
      out.push_back(&t);
    }
  }
  return out;
}

// log N_k(x; m·1, s² 11ᵀ + D) by Sherman–Morrison (D diagonal).
double LogCommonShift(const std::vector<const EvidenceTerm*>& members, double mean, double spread) {
  double log_det_d = 0.0, sum_inv = 0.0, quad_d = 0.0, lin = 0.0;
  for (const auto* t : members) {
    const double d = t->healthy_sd * t->healthy_sd + t->measurement_sd * t->measurement_sd;
    const double r = t->x - mean;
    log_det_d += std::log(d);
    sum_inv += 1.0 / d;
    quad_d += r * r / d;
    lin += r / d;
  }
  const double s2 = spread * spread;
  const double denom = 1.0 + s2 * sum_inv;
  const double quad = quad_d - s2 * lin * lin / denom;
  const double k = static_cast<double>(members.size());
  return -0.5 * (k * std::log(2.0 * std::numbers::pi) + log_det_d + std::log(denom) + quad);
}

// The density of a standard score x that a hypothesis predicts at about
// ±change with `spread` (and `extra_var` from the measurement and the
// healthy scatter), averaged over the directions `signs`. An effect that is
// present has no one expected score: its size against its error grows with
// the fault and with what the run measures of it (a bias jump of 60 drift σ
// scores 75 in an hour at 20 Hz). So its magnitude is spread evenly over
// `octaves` doublings above the change, each with the spread scaled alike: a
// log-uniform size, the scale-invariant prior of a magnitude (Jeffreys,
// Theory of Probability, 3rd ed. 1961, §3.1), and a stronger detection never
// counts against the mode. octaves = 0: N(±change, spread² + extra_var).
double LogPresentScore(double x, const std::vector<double>& signs, double change, double spread,
                       double extra_var, int octaves) {
  const int components = 1 + std::max(0, octaves);
  const double log_share =
      -std::log(static_cast<double>(signs.size() * static_cast<std::size_t>(components)));
  double total = -INFINITY;
  for (int j = 0; j < components; ++j) {
    const double scale = std::ldexp(1.0, j);
    const double var = (spread * scale) * (spread * scale) + extra_var;
    for (double sign : signs)
      total = LogAddExp(total, log_share + LogNormalPdf(x, sign * change * scale, var));
  }
  return total;
}

double LogSignatureTerm(const Signature& term, const std::vector<const EvidenceTerm*>& members,
                        const DiagnosisSettings& settings) {
  const auto signs = internal::SignsOf(term.direction);
  const double log_share = -std::log(static_cast<double>(signs.size()));
  if (term.common && members.size() > 1) {
    double total = -INFINITY;
    for (double sign : signs) total = LogAddExp(total, log_share + LogCommonShift(members, sign * term.change, term.spread));
    return total;
  }
  const double q = term.fraction > 0.0 ? std::min(term.fraction, 1.0) : 1.0;
  double sum = 0.0;
  for (const auto* t : members) {
    const double extra_var = t->healthy_sd * t->healthy_sd + t->measurement_sd * t->measurement_sd;
    const int octaves = t->scale == Scale::kZ ? settings.present_score_octaves : 0;
    const double moved =
        LogPresentScore(t->x, signs, term.change, term.spread, extra_var, octaves);
    sum += q < 1.0 ? LogAddExp(std::log(q) + moved, std::log1p(-q) + HealthyLog(*t)) : moved;
  }
  return sum;
}

// A significant trend of a parameter the signature term reads: a fault
// developing over the unit's runs moves it in the term's direction, its
// standard score about ±μ_T with spread s_T (DiagnosisSettings.trend_z_*),
// or more: a score of a present effect (LogPresentScore).
double LogTrendTerm(const Signature& term, const EvidenceTerm& t, const DiagnosisSettings& settings) {
  return LogPresentScore(t.x, internal::SignsOf(term.direction), settings.trend_z_change,
                         settings.trend_z_spread, t.healthy_sd * t.healthy_sd,
                         settings.present_score_octaves);
}

// The signature term of `mode` that reads the parameter trend term `t` is
// the trend of, or nullptr.
const Signature* TrendReader(const FailureMode& mode, const EvidenceTerm& t) {
  if (t.trend_of.empty()) return nullptr;
  for (const auto& term : mode.signature) {
    if (SignatureCovers(term.parameter, t.trend_of)) return &term;
  }
  return nullptr;
}

// The unit's own significant trends in parameters the mode's signature
// reads: their log-likelihood, each marked `covered`, with its line.
double LogTrendTerms(const FailureMode& mode, const Evidence& evidence, const DiagnosisSettings& settings,
                     std::vector<bool>& covered, std::vector<std::string>& lines) {
  double ll = 0.0;
  for (std::size_t i = 0; i < evidence.terms.size(); ++i) {
    const Signature* reader = TrendReader(mode, evidence.terms[i]);
    if (reader == nullptr) continue;
    covered[i] = true;
    ll += LogTrendTerm(*reader, evidence.terms[i], settings);
    lines.push_back(absl::StrCat(evidence.terms[i].line, ", as a developing ", reader->parameter, " shift predicts"));
  }
  return ll;
}

// "gyro_scale_factor.{x,y,z}: +9.6, +9.5, +9.7 tolerance units" for a family.
std::string FamilyLine(const Signature& term, const std::vector<const EvidenceTerm*>& members) {
  std::vector<std::string> axes, values;
  bool all_significant = true;
  int positive = 0;
  for (const auto* t : members) {
    const std::optional<engine::ParameterKey> key = engine::ParseParameterKey(t->name);
    axes.push_back(key ? key->axes : t->name);
    values.push_back(SignedFormat(t->x));
    all_significant = all_significant && (t->scale != Scale::kTolerance || t->significant ||
                                          std::abs(t->x) > 3.0 * std::max(t->measurement_sd, 1e-12));
    positive += t->x > 0 ? 1 : 0;
  }
  const std::string family = term.parameter.substr(0, term.parameter.size() - 2);
  const char* unit = term.scale == Scale::kLogRatio ? " (log-ratio to nominal)"
                     : term.scale == Scale::kZ       ? " standard errors"
                                                 : " tolerance units";
  std::string line = absl::StrCat(family, ".{", absl::StrJoin(axes, ","), "}: ", absl::StrJoin(values, ", "), unit);
  if (members.size() > 1 && (positive == 0 || positive == static_cast<int>(members.size()))) {
    absl::StrAppend(&line, ", all ", positive > 0 ? "positive" : "negative");
  }
  if (all_significant) absl::StrAppend(&line, ", significant");
  return line;
}

std::vector<std::string> ModeEvidenceLines(const FailureMode& mode, const Evidence& evidence) {
  std::vector<std::string> lines;
  for (const auto& term : mode.signature) {
    const auto members = Members(term, evidence);
    if (members.empty()) {
      lines.push_back(absl::StrCat(term.parameter, ": not measured by this analysis"));
      continue;
    }
    if (IsFamily(term.parameter) && members.size() > 1) lines.push_back(FamilyLine(term, members));
    for (const auto* t : members) lines.push_back(t->line);
  }
  return lines;
}

// The terms furthest from healthy, as lines.
std::vector<std::string> LargestDeviations(const Evidence& evidence, std::size_t count) {
  std::vector<const EvidenceTerm*> sorted;
  for (const auto& t : evidence.terms) sorted.push_back(&t);
  std::sort(sorted.begin(), sorted.end(), [](const EvidenceTerm* a, const EvidenceTerm* b) {
    const auto z = [](const EvidenceTerm* t) {
      return std::abs(t->x) / std::hypot(t->healthy_sd, t->measurement_sd);
    };
    return z(a) > z(b);
  });
  std::vector<std::string> lines;
  for (std::size_t i = 0; i < std::min(count, sorted.size()); ++i) lines.push_back(sorted[i]->line);
  return lines;
}

std::string ModuleOfHypothesis(const Hypothesis& h) { return h.module; }

}  // namespace

bool SignatureCovers(const std::string& pattern, const std::string& name) {
  if (!IsFamily(pattern)) return pattern == name;
  // "family.*" covers the family's terms themselves, not their fields.
  const std::optional<engine::ParameterKey> family = engine::ParseParameterKey(pattern);
  const std::optional<engine::ParameterKey> key = engine::ParseParameterKey(name);
  return family && key && key->family == family->family && key->IsBareTerm() && !key->axes.empty();
}

DiagnosisHeadline HeadlineOf(const Diagnosis& diagnosis) {
  DiagnosisHeadline out;
  double healthy = 0.0;
  for (const Hypothesis& h : diagnosis.hypotheses) {
    if (h.failure_mode == kHealthy) healthy = h.probability;
  }
  out.fault_probability = 1.0 - healthy;
  for (const Candidate& c : diagnosis.candidates) {
    if (c.module != kHealthy) {
      out.top = &c;
      break;
    }
  }
  return out;
}

double ModeRatePerHour(const FailureMode& mode, std::int64_t confirmed_failures, double fleet_exposure_hours,
                       const DiagnosisSettings& settings) {
  const double h0 = settings.expert_pseudo_hours;
  const double expert_per_hour = mode.expert_rate_per_million_hours * 1e-6;
  return (static_cast<double>(confirmed_failures) + expert_per_hour * h0) / (std::max(fleet_exposure_hours, 0.0) + h0);
}

namespace {

// A hypothesis with its log-posterior and the lines that say why.
struct ScoredHypothesis {
  Hypothesis hypothesis;
  std::vector<std::string> evidence;
  double log_posterior = 0.0;
};

ScoredHypothesis Scored(const std::string& name, const std::string& module, double prior,
                        double log_likelihood, std::vector<std::string> lines) {
  ScoredHypothesis s;
  s.hypothesis.failure_mode = name;
  s.hypothesis.module = module;
  s.hypothesis.prior = prior;
  s.hypothesis.log_likelihood = log_likelihood;
  s.evidence = std::move(lines);
  s.log_posterior = std::log(prior) + log_likelihood;
  return s;
}

void CopyEvidence(const Evidence& evidence, Diagnosis& out) {
  out.notes = evidence.notes;
  for (const EvidenceTerm& t : evidence.terms) {
    EvidenceItem item;
    item.name = t.name;
    item.scale = t.scale;
    item.value = t.x;
    item.measurement_sd = t.measurement_sd;
    item.healthy_sd = t.healthy_sd;
    item.significant = t.significant;
    out.evidence.push_back(std::move(item));
  }
}

// Per evidence term, its log-likelihood when it is off as a fault's knock-on
// and when it is off by chance (docs/DIAGNOSIS.md, "Hypotheses").
struct Contamination {
  std::vector<double> knock_on, incidental;
};

// A pair's joint density, its first term read by `first_reader` and its
// second by `second_reader` (nullptr: left at healthy, off with probability
// `off_probability`).
double LogPair(const Evidence& evidence, std::size_t first, std::size_t second,
               const Signature* first_reader, const Signature* second_reader, double off_probability,
               const DiagnosisSettings& settings) {
  return internal::LogPairDensity({internal::PairComponent{&evidence.terms[first], first_reader, off_probability},
                                   internal::PairComponent{&evidence.terms[second], second_reader, off_probability}},
                                  evidence.terms[first].measurement_correlation, settings);
}

// Per term, its log-likelihood under `healthy` and off as a knock-on or by
// chance; a pair's joint value stands at its first term, 0 at its second.
struct TermLikelihoods {
  std::vector<double> healthy;
  Contamination contamination;
};

TermLikelihoods LikelihoodsOfTerms(const Evidence& evidence,
                                   const std::vector<std::optional<std::size_t>>& partners,
                                   const DiagnosisSettings& settings) {
  TermLikelihoods out;
  for (std::size_t i = 0; i < evidence.terms.size(); ++i) {
    const EvidenceTerm& t = evidence.terms[i];
    if (!partners[i]) {
      out.healthy.push_back(HealthyLog(t));
      out.contamination.knock_on.push_back(ContaminatedLog(t, settings.contamination, settings));
      out.contamination.incidental.push_back(ContaminatedLog(t, settings.incidental_contamination, settings));
    } else if (*partners[i] > i) {
      const std::size_t j = *partners[i];
      out.healthy.push_back(LogPair(evidence, i, j, nullptr, nullptr, 0.0, settings));
      out.contamination.knock_on.push_back(LogPair(evidence, i, j, nullptr, nullptr, settings.contamination, settings));
      out.contamination.incidental.push_back(
          LogPair(evidence, i, j, nullptr, nullptr, settings.incidental_contamination, settings));
    } else {
      out.healthy.push_back(0.0);
      out.contamination.knock_on.push_back(0.0);
      out.contamination.incidental.push_back(0.0);
    }
  }
  return out;
}

// A failure mode's log-likelihood: its signature's terms, its trends, and
// every other term as a knock-on on the sensor axes the signature reads and
// as incidental elsewhere, so that a mode's odds against `healthy` do not
// fall with the number of terms it does not read.
double ModeLogLikelihood(const FailureMode& mode, const Evidence& evidence,
                         const std::vector<std::optional<std::size_t>>& partners,
                         const Contamination& contamination, const DiagnosisSettings& settings,
                         std::vector<std::string>& trend_lines) {
  std::vector<bool> covered(evidence.terms.size(), false);
  std::vector<const Signature*> pair_readers(evidence.terms.size(), nullptr);
  std::set<std::string> own_sensor_axes;  // the sensor axes the signature reads
  double ll = 0.0;
  for (const auto& term : mode.signature) {
    std::vector<const EvidenceTerm*> alone;
    for (const auto* t : Members(term, evidence)) {
      const auto i = static_cast<std::size_t>(t - evidence.terms.data());
      covered[i] = true;
      own_sensor_axes.insert(SensorAxisOf(t->name));
      if (partners[i]) {
        pair_readers[i] = &term;
      } else {
        alone.push_back(t);
      }
    }
    if (!alone.empty()) ll += LogSignatureTerm(term, alone, settings);
  }
  // A pair the signature reads in part or whole: jointly, its unread term
  // off as a knock-on (it is on the same sensor axis).
  for (std::size_t i = 0; i < evidence.terms.size(); ++i) {
    if (!partners[i] || *partners[i] < i) continue;
    const std::size_t j = *partners[i];
    if (pair_readers[i] == nullptr && pair_readers[j] == nullptr) continue;
    covered[i] = covered[j] = true;
    ll += LogPair(evidence, i, j, pair_readers[i], pair_readers[j], settings.contamination, settings);
  }
  ll += LogTrendTerms(mode, evidence, settings, covered, trend_lines);
  for (std::size_t i = 0; i < evidence.terms.size(); ++i) {
    if (covered[i]) continue;
    ll += own_sensor_axes.contains(SensorAxisOf(evidence.terms[i].name))
              ? contamination.knock_on[i]
              : contamination.incidental[i];
  }
  return ll;
}

// The hypotheses normalised (log-sum-exp), most probable first, and the
// modules ranked by the sum over their modes; a module's most probable mode
// speaks for it.
void RankHypothesesAndModules(std::vector<ScoredHypothesis>& scored, Diagnosis& out) {
  double log_total = -INFINITY;
  for (const auto& s : scored) log_total = LogAddExp(log_total, s.log_posterior);
  for (auto& s : scored) s.hypothesis.probability = std::exp(s.log_posterior - log_total);
  std::stable_sort(scored.begin(), scored.end(),
                   [](const ScoredHypothesis& a, const ScoredHypothesis& b) {
                     return a.hypothesis.probability > b.hypothesis.probability;
                   });
  std::map<std::string, std::pair<double, const ScoredHypothesis*>> modules;
  for (const auto& s : scored) {
    out.hypotheses.push_back(s.hypothesis);
    auto& [p, best] = modules[ModuleOfHypothesis(s.hypothesis)];
    p += s.hypothesis.probability;
    if (best == nullptr) best = &s;
  }
  std::vector<std::pair<std::string, std::pair<double, const ScoredHypothesis*>>> ranked(
      modules.begin(), modules.end());
  std::stable_sort(ranked.begin(), ranked.end(),
                   [](const auto& a, const auto& b) { return a.second.first > b.second.first; });
  for (const auto& [module, entry] : ranked) {
    Candidate c;
    c.module = module;
    c.failure_mode = entry.second->hypothesis.failure_mode;
    c.probability = entry.first;
    c.evidence = entry.second->evidence;
    out.candidates.push_back(std::move(c));
  }
}

}  // namespace

Diagnosis Diagnose(const Evidence& evidence, std::span<const FailureMode> modes,
                       const DiagnosisSettings& settings, const PriorInputs& prior) {
  Diagnosis out;
  CopyEvidence(evidence, out);

  // Priors.
  std::vector<double> rates;
  double total_rate = 0.0;
  for (const auto& mode : modes) {
    const auto it = prior.confirmed_failures.find(mode.name);
    rates.push_back(ModeRatePerHour(mode, it == prior.confirmed_failures.end() ? 0 : it->second,
                                    prior.fleet_exposure_hours, settings));
    total_rate += rates.back();
  }
  const double exposure = std::max(prior.exposure_hours, settings.minimum_exposure_hours);
  const double u = settings.unknown_prior;
  const double p_any = -std::expm1(-total_rate * exposure);

  std::vector<ScoredHypothesis> scored;
  if (evidence.terms.empty()) {
    // Without evidence the modes cannot be told apart: healthy or unknown, by the verdict.
    const bool good = evidence.verdict == engine::Verdict::kGood;
    // A finite stand-in for log 0 (JSON has no infinities).
    scored.push_back(
        Scored(kHealthy, kHealthy, (1.0 - u), good ? 0.0 : -1e300,
                   {good ? "verdict GOOD: the model fits the run" : "the verdict is not GOOD"}));
    scored.push_back(
        Scored(kUnknown, kUnknown, u, 0.0,
                   {absl::StrCat("verdict ", evidence.verdict ? engine::VerdictName(*evidence.verdict) : "VERDICT_UNSPECIFIED",
                                 ", and no identified parameter or effect candidate to say why")}));
  } else {
    const std::vector<std::optional<std::size_t>> partners = internal::PartnersOf(evidence);
    const TermLikelihoods terms = LikelihoodsOfTerms(evidence, partners, settings);
    const Contamination& contamination = terms.contamination;
    double healthy_ll = 0.0, unknown_ll = 0.0;
    for (std::size_t i = 0; i < evidence.terms.size(); ++i) {
      healthy_ll += terms.healthy[i];
      unknown_ll += contamination.knock_on[i];
    }
    std::vector<std::string> healthy_lines = {absl::StrCat(evidence.terms.size(), " evidence terms; furthest from nominal:")};
    for (auto& l : LargestDeviations(evidence, 3)) healthy_lines.push_back(std::move(l));
    scored.push_back(
        Scored(kHealthy, kHealthy, (1.0 - u) * (1.0 - p_any), healthy_ll, healthy_lines));
    std::vector<std::string> unknown_lines = {"evidence no failure mode of this unit type explains:"};
    for (auto& l : LargestDeviations(evidence, 3)) unknown_lines.push_back(std::move(l));
    scored.push_back(Scored(kUnknown, kUnknown, u, unknown_ll, unknown_lines));
    for (std::size_t m = 0; m < modes.size(); ++m) {
      const auto& mode = modes[m];
      std::vector<std::string> trend_lines;
      const double ll = ModeLogLikelihood(mode, evidence, partners, contamination, settings, trend_lines);
      const double p = total_rate > 0 ? (1.0 - u) * p_any * rates[m] / total_rate : 0.0;
      std::vector<std::string> lines = ModeEvidenceLines(mode, evidence);
      for (auto& line : trend_lines) lines.push_back(std::move(line));
      scored.push_back(Scored(mode.name, mode.module_role, p, ll, std::move(lines)));
    }
  }
  RankHypothesesAndModules(scored, out);
  return out;
}

std::optional<double> CaseValue(const Signature& term, const Evidence& evidence) {
  const auto members = Members(term, evidence);
  if (members.empty()) return std::nullopt;
  double sum = 0.0;
  for (const auto* t : members) sum += t->x;
  const double mean = sum / static_cast<double>(members.size());
  switch (term.direction) {
    case Direction::kUp: return mean;
    case Direction::kDown: return -mean;
    case Direction::kEither: break;
  }
  if (term.common) return std::abs(mean);
  double abs_sum = 0.0;
  for (const auto* t : members) abs_sum += std::abs(t->x);
  return abs_sum / static_cast<double>(members.size());
}

Signature RefineSignature(const Signature& term, std::span<const double> case_values,
                              const DiagnosisSettings& settings) {
  Signature out = term;
  const double mu0 = term.expert_change;
  const double s0 = term.expert_spread;
  const double k0 = settings.expert_signature_weight;
  const double n = static_cast<double>(case_values.size());
  out.confirmed_cases = static_cast<int>(case_values.size());
  if (case_values.empty()) {
    out.change = mu0;
    out.spread = s0;
    return out;
  }
  double mean = 0.0;
  for (double c : case_values) mean += c;
  mean /= n;
  double ss = 0.0;
  for (double c : case_values) ss += (c - mean) * (c - mean);
  const double mu = (k0 * mu0 + n * mean) / (k0 + n);
  const double s2 = (k0 * s0 * s0 + ss + k0 * n * (mean - mu0) * (mean - mu0) / (k0 + n)) / (k0 + n);
  out.change = std::max(mu, 0.0);
  out.spread = std::sqrt(s2);
  return out;
}

}  // namespace insdiag::kb
