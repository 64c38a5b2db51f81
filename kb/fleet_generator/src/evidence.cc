// What a planned test measures — the unit's identified parameters and effect
// statistics, from its batch, its own offset, ageing, the precursors of its
// coming failures and the test's scatter — and the analysis report that
// carries it, as the engine would write it.
#include <algorithm>
#include <cmath>
#include <numbers>

#include "generator.h"
#include "insdiag/engine/candidate_source.h"

namespace insdiag::kb::generator {
namespace {

// Two-sided normal p-value of a standard score.
double PValue(double z) { return std::erfc(std::abs(z) / std::numbers::sqrt2); }

}  // namespace

double PrecursorShare(const Model& m, std::int64_t ahead_us) {
  if (ahead_us < 0 || ahead_us >= m.precursor_us) return 0.0;
  const double elapsed = 1.0 - static_cast<double>(ahead_us) / static_cast<double>(m.precursor_us);
  return std::pow(elapsed, m.profile.precursor_exponent());
}

TestValues Measure(const Model& m, const Plan& plan, std::size_t unit, std::size_t test) {
  const UnitPlan& u = plan.units[unit];
  const Test& t = u.tests[test];
  const Batch& b = plan.batches[static_cast<std::size_t>(u.batch)];
  const v1::FleetProfile& p = m.profile;
  TestValues v;
  v.log_ratio.assign(m.identified.size(), 0.0);
  v.effect_x.assign(m.effects.size(), 0.0);
  v.moving.assign(m.effects.size(), false);
  // Drifts of parts failing within the precursor window.
  for (const auto& f : u.failures) {
    const Part& part = u.parts[static_cast<std::size_t>(f.part)];
    if (t.time_us < part.installed_us || t.time_us > f.time_us || f.time_us - t.time_us >= m.precursor_us) continue;
    const double share = PrecursorShare(m, f.time_us - t.time_us);
    for (const auto& s : f.shifts) {
      if (s.kind == TermKind::kIdentified) {
        v.log_ratio[static_cast<std::size_t>(s.index)] += share * s.value;
      } else {
        v.effect_x[static_cast<std::size_t>(s.index)] += share * s.value;
        v.moving[static_cast<std::size_t>(s.index)] = true;
      }
    }
  }
  Rng rng(m.seed, kTestStream, (static_cast<std::uint64_t>(unit) << 24) | test);
  const double age_years = static_cast<double>(t.time_us - u.commission_us) / kMicrosPerYear;
  const double measurement_sd = std::sqrt(p.measurement_variance_share());
  double worst = 0, excess = 0;
  for (std::size_t i = 0; i < m.identified.size(); ++i) {
    const IdentifiedTerm& term = m.identified[i];
    v.log_ratio[i] += b.offset[i] + u.offset[i] + b.ageing[i] * age_years + measurement_sd * term.healthy_sd * rng.Normal();
    const double tolerances = std::abs(term.nominal * std::expm1(v.log_ratio[i])) / term.tolerance;
    worst = std::max(worst, tolerances);
    excess += std::pow(std::max(tolerances - 1.0, 0.0), 2);
  }
  const double m_tests = static_cast<double>(m.effects.size());
  bool significant = false;
  for (std::size_t i = 0; i < m.effects.size(); ++i) {
    const EffectTerm& e = m.effects[i];
    v.effect_x[i] += (e.scored() ? m.settings.healthy_z_sd : m.settings.healthy_tolerance_sd) * rng.Normal();
    if (e.scored()) {
      significant = significant || PValue(v.effect_x[i]) * m_tests < m.settings.significance_level;
    } else {
      worst = std::max(worst, std::abs(v.effect_x[i]));
      excess += std::pow(std::max(std::abs(v.effect_x[i]) - 1.0, 0.0), 2);
    }
  }
  v.verdict = worst <= 1.0 && !significant         ? v1::AnalysisReport::GOOD
              : worst <= p.operable_tolerances() ? v1::AnalysisReport::OPERABLE
                                                   : v1::AnalysisReport::FAULTY;
  const double terms = static_cast<double>(m.identified.size() + m.effects.size());
  v.nis_mean = (1.0 + p.nis_mean_sd() * rng.Normal()) * (1.0 + excess / std::max(terms, 1.0));
  return v;
}

// The candidates a test's analysis carries: every effect for the analyses
// that are diagnosed, else the moving ones. Holm's adjustment over all the
// unit type's effects, the unwritten ones (not moving) taken as less
// significant than the written.
std::vector<CandidateRow> Candidates(const Model& m, const TestValues& v, bool all) {
  std::vector<CandidateRow> rows;
  for (std::size_t i = 0; i < m.effects.size(); ++i) {
    if (!all && !v.moving[i]) continue;
    const EffectTerm& e = m.effects[i];
    CandidateRow r;
    r.effect = static_cast<int>(i);
    r.std_error = e.scored() ? e.std_error : m.profile.effect_std_error_tolerances() * e.tolerance;
    const double z = e.scored() ? v.effect_x[i] : v.effect_x[i] / m.profile.effect_std_error_tolerances();
    r.estimate = z * r.std_error;
    r.statistic = z * z;
    r.p_value = PValue(z);
    rows.push_back(r);
  }
  std::sort(rows.begin(), rows.end(), [](const CandidateRow& a, const CandidateRow& b) { return a.p_value < b.p_value; });
  double running = 0;
  for (std::size_t k = 0; k < rows.size(); ++k) {
    running = std::max(running, std::min(1.0, static_cast<double>(m.effects.size() - k) * rows[k].p_value));
    rows[k].p_holm = running;
  }
  return rows;
}

double IdentifiedValue(const IdentifiedTerm& t, double log_ratio) { return t.nominal * std::exp(log_ratio); }
double IdentifiedStdError(const Model& m, const IdentifiedTerm& t, double value) {
  return value * std::sqrt(m.profile.measurement_variance_share()) * t.healthy_sd;
}

v1::AnalysisReport ReportOf(const Model& m, const TestValues& v) {
  v1::AnalysisReport report;
  report.set_verdict(v.verdict);
  report.set_nis_mean(v.nis_mean);
  for (std::size_t i = 0; i < m.identified.size(); ++i) {
    const IdentifiedTerm& t = m.identified[i];
    auto* p = report.add_identified();
    p->set_name(t.name);
    p->set_value(IdentifiedValue(t, v.log_ratio[i]));
    p->set_std_error(IdentifiedStdError(m, t, p->value()));
    v1::IdentifiedParameter::Method method = v1::IdentifiedParameter::METHOD_UNSPECIFIED;
    v1::IdentifiedParameter::Method_Parse(t.method, &method);
    p->set_method(method);
    p->set_unit(t.unit);
    p->set_a_priori(t.nominal);
  }
  for (const auto& r : Candidates(m, v, true)) {
    const EffectTerm& e = m.effects[static_cast<std::size_t>(r.effect)];
    auto* c = report.add_effect_candidates();
    c->set_name(e.name);
    c->set_family(e.family);
    c->set_unit(e.unit);
    c->set_source(std::string(engine::CandidateSourceName(engine::CandidateSource::kScore)));
    c->set_statistic(r.statistic);
    c->set_degrees_of_freedom(1);
    c->set_p_value(r.p_value);
    c->set_p_value_holm(r.p_holm);
    c->set_estimate(r.estimate);
    c->set_std_error(r.std_error);
    c->set_identifiable(true);
  }
  return report;
}

}  // namespace insdiag::kb::generator
