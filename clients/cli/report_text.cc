#include "report_text.h"

#include <absl/strings/str_format.h>

#include <algorithm>
#include <charconv>
#include <string>

#include "insdiag/api/report_codec.h"
#include "insdiag/engine/filter/observation.h"
#include "insdiag/engine/ident/correlation.h"

namespace insdiag::cli {
namespace {

void AppendNumber(std::string& line, double v) {
  char buf[32];
  const auto [end, ec] = std::to_chars(buf, buf + sizeof buf, v);
  line.append(buf, ec == std::errc() ? end : buf);
}

}  // namespace

std::string ObservabilityText(v1::IdentifiedParameter::Observability verdict, const std::string& note) {
  switch (verdict) {
    case v1::IdentifiedParameter::OBSERVABLE: return "observable";
    case v1::IdentifiedParameter::NOT_EXCITED: return "NOT observable: not excited, " + note;
    case v1::IdentifiedParameter::INSEPARABLE: return "NOT observable: inseparable, " + note;
    case v1::IdentifiedParameter::WEAKLY_DETERMINED: return "NOT observable: weakly determined, " + note;
    default: return "";
  }
}

void PrintReport(const engine::AnalysisReport& r, std::ostream& out) {
  out << "verdict: " << engine::VerdictName(r.verdict) << "\n";
  if (!r.plain_words.empty()) {
    out << "\nin plain words:\n";
    for (const std::string& line : r.plain_words) out << "  " << line << "\n";
    out << "\n";
  }
  out << "model: base";
  for (const auto& e : r.model_effects) out << " + " << e;
  out << "  (" << r.parameter_count << " parameters)\n";
  out << "run: " << r.samples << " samples over " << absl::StrFormat("%.0f", r.duration_s)
      << " s at " << absl::StrFormat("%.4g", r.sample_rate_hz) << " Hz, updates every "
      << absl::StrFormat("%.3g", r.update_interval_s) << " s\n";
  out << "NIS mean " << absl::StrFormat("%.4f", r.fit.nis_mean) << " (band "
      << absl::StrFormat("%.4f", r.nis_band_low) << " … "
      << absl::StrFormat("%.4f", r.nis_band_high) << "), log-likelihood "
      << absl::StrFormat("%.2f", r.fit.log_likelihood) << ", AIC " << absl::StrFormat("%.2f", r.fit.aic)
      << ", BIC " << absl::StrFormat("%.2f", r.fit.bic) << "\n\n";
  out << "channel   unit   residual RMS   fit %   NIS mean   whiteness p   β²>γ²\n";
  for (const auto& c : r.channels) {
    out << absl::StrFormat("%-8s  %-5s  %12.4g  %6.1f  %9.4f  %12.3g  %5.1f%%\n", c.name, c.unit,
                           c.rms, c.fit_percent, c.nis_mean, c.whiteness_p_value,
                           100.0 * c.fraction_over_gamma2);
  }
  if (!r.faults.empty()) {
    out << "\nwhere the model fails (γ² = " << absl::StrFormat("%.2f", r.gamma2)
        << ", η² = " << absl::StrFormat("%.3f", r.eta2) << "):\n";
    for (const auto& f : r.faults) {
      out << "  " << engine::FaultKindName(f.kind) << " " << f.channel << " "
          << absl::StrFormat("%.2f", f.start_s) << " … " << absl::StrFormat("%.2f", f.end_s)
          << " s (peak " << absl::StrFormat("%.3g", f.peak_statistic) << ")\n";
    }
  }
  if (!r.bench_motion.empty()) {
    out << "\nwhere the bench moved (its updates are not held against the unit):\n";
    for (const auto& m : r.bench_motion) {
      out << "  " << engine::kSensorChannelNames[static_cast<size_t>(m.sensor_channel)] << " "
          << absl::StrFormat("%.2f", m.start_s) << " … " << absl::StrFormat("%.2f", m.end_s)
          << " s (scatter " << absl::StrFormat("%.3g", m.statistic) << " σ over its quiet level)\n";
    }
  }
  for (const auto& l : r.localisation) {
    // A ramp's estimate is a rate from its onset, not a jump.
    const bool ramp = l.state.find("_bias_ramp.") != std::string::npos;
    out << "  failed sensor: " << l.state << (ramp ? " drifting at " : " jumped by ")
        << absl::StrFormat("%.3g", l.jump) << " ± " << absl::StrFormat("%.2g", l.jump_std_error)
        << (ramp ? " per s from " : " at ") << absl::StrFormat("%.1f", l.time_s) << " s (p "
        << absl::StrFormat("%.2g", l.p_value) << ")\n";
  }
  if (!r.discrepancies.empty()) {
    out << "\nforward/backward discrepancies:\n";
    for (const auto& d : r.discrepancies) {
      out << "  " << d.state << " at " << absl::StrFormat("%.1f", d.time_s)
          << " s: " << absl::StrFormat("%.1f", d.statistic) << " (p "
          << absl::StrFormat("%.2g", d.p_value) << ")\n";
    }
  }
  if (!r.effect_candidates.empty()) {
    out << "\nmissing effects, most significant first:\n";
    int shown = 0;
    for (const auto& c : r.effect_candidates) {
      if (shown++ == 10) break;
      out << "  " << c.name << "  " << (c.identifiable ? "" : "(not ranked: see below) ")
          << "estimate " << absl::StrFormat("%.3g", c.estimate) << " ± "
          << absl::StrFormat("%.2g", c.std_error) << " " << c.unit << ", statistic "
          << absl::StrFormat("%.1f", c.statistic) << ", p "
          << absl::StrFormat("%.2g", c.p_value_holm) << " (Holm), ΔAIC "
          << absl::StrFormat("%.1f", c.predicted_delta_aic) << "\n";
      if (!c.correlated_with.empty()) {
        out << "      not told apart in this run from:";
        for (const auto& other : c.correlated_with) out << " " << other;
        out << "\n";
      }
      if (!c.note.empty()) out << "      " << c.note << "\n";
    }
  }
  if (!r.identified.empty()) {
    out << "\nidentified parameters:\n";
    for (const auto& p : r.identified) {
      out << "  " << p.name << " = " << absl::StrFormat("%.4g", p.value) << " ± "
          << absl::StrFormat("%.2g", p.std_error) << " " << p.unit << " ["
          << (p.method.has_value() ? engine::MethodName(*p.method) : "") << "]";
      if (p.a_priori == p.a_priori)
        out << " (a priori " << absl::StrFormat("%.4g", p.a_priori) << ")";
      const api::Observability observability = api::ObservabilityOf(p);
      if (const std::string text = ObservabilityText(observability.verdict, observability.note); !text.empty()) {
        out << " " << text;
      }
      out << "\n";
    }
  }
  if (r.comparison.has_value()) {
    const engine::ModelComparison& c = *r.comparison;
    out << "\nbefore → after (added:";
    for (const auto& e : c.added_effects) out << " " << e;
    out << ")\n";
    out << "  NIS mean " << absl::StrFormat("%.4f", c.before.nis_mean) << " → "
        << absl::StrFormat("%.4f", c.after.nis_mean) << ", AIC "
        << absl::StrFormat("%.1f", c.before.aic) << " → " << absl::StrFormat("%.1f", c.after.aic)
        << ", BIC " << absl::StrFormat("%.1f", c.before.bic) << " → "
        << absl::StrFormat("%.1f", c.after.bic) << "\n";
    out << "  2ΔlogL realised " << absl::StrFormat("%.1f", c.realized_lr)
        << ", predicted by the score test " << absl::StrFormat("%.1f", c.predicted_lr) << "\n";
    out << "  channel   RMS before → after        NIS before → after   whiteness p before → after\n";
    for (const auto& ch : c.channels) {
      out << "  " << ch.name << std::string(8 - std::min<size_t>(8, ch.name.size()), ' ')
          << absl::StrFormat("%10.4g", ch.before.rms) << " → "
          << absl::StrFormat("%-10.4g", ch.after.rms) << "  "
          << absl::StrFormat("%8.4f", ch.before.nis_mean) << " → "
          << absl::StrFormat("%-8.4f", ch.after.nis_mean) << "  "
          << absl::StrFormat("%8.3g", ch.before.whiteness_p_value) << " → "
          << absl::StrFormat("%.3g", ch.after.whiteness_p_value) << "\n";
    }
  }
  if (!r.discovery.empty()) {
    out << "\ndiscovery path:\n";
    for (const auto& d : r.discovery) {
      out << "  step " << d.step << ": + " << d.effect << " (statistic "
          << absl::StrFormat("%.1f", d.statistic) << ", Holm p "
          << absl::StrFormat("%.2g", d.p_value) << ")  → NIS "
          << absl::StrFormat("%.4f", d.fit.nis_mean) << ", AIC " << absl::StrFormat("%.1f", d.fit.aic)
          << "\n";
      for (const auto& e : d.estimates) {
        out << "      " << e.name << " = " << absl::StrFormat("%.4g", e.value) << " ± "
            << absl::StrFormat("%.2g", e.std_error) << " " << e.unit << "\n";
      }
    }
  }
  for (const auto& n : r.notes) out << "note: " << n << "\n";
}

void WriteCorrelationCsv(const engine::AnalysisReport& r, std::ostream& out) {
  out << "state,lag_s,acf,band,error_acf,family,fit\n";
  for (const engine::DriftCorrelation& d : r.correlation) {
    const auto& a = d.analysis;
    for (size_t j = 0; j < a.acf.size(); ++j) {
      const double band = j < a.acf_band.size() ? a.acf_band[j] : 0.0;
      const double error = j < a.error_acf.size() ? a.error_acf[j] : 0.0;
      for (const auto& f : a.fits) {
        if (!f.usable || j >= f.expected.size()) continue;
        std::string line = d.state + ",";
        AppendNumber(line, static_cast<double>(j) * a.dt_s);
        for (double v : {a.acf[j], band, error}) {
          line += ",";
          AppendNumber(line, v);
        }
        line += ",";
        line += engine::ident::CorrelationFamilyName(f.family);
        line += ",";
        AppendNumber(line, f.expected[j]);
        out << line << "\n";
      }
    }
  }
}

void WriteAllanCsv(const engine::AnalysisReport& r, std::ostream& out) {
  out << "channel,tau_s,adev,adev_low,adev_high,fitted\n";
  if (!r.allan.has_value()) return;
  for (const auto& ch : r.allan->channels) {
    for (const auto& p : ch.curve) {
      std::string line = ch.name;
      for (double v : {p.tau_s, p.adev, p.ci_low, p.ci_high, p.fitted_adev}) {
        line += ",";
        AppendNumber(line, v);
      }
      out << line << "\n";
    }
  }
}

void WriteSeriesCsv(const engine::AnalysisSeries& s, std::ostream& out) {
  std::string line = "t";
  for (const auto& name : engine::kChannelNames) {
    for (const char* q : {"_measured", "_predicted", "_residual", "_sigma3"}) {
      line += ",";
      line += name;
      line += q;
    }
  }
  out << line << "\n";
  for (size_t k = 0; k < s.time_s.size(); ++k) {
    const auto e = static_cast<Eigen::Index>(k);
    line.clear();
    AppendNumber(line, s.time_s[k]);
    for (int c = 0; c < engine::kChannelCount; ++c) {
      const bool observed = s.sigma(e, c) > 0.0;  // the attitude is observed while the table stands still
      for (double v : {s.measured(e, c), s.predicted(e, c), s.residual(e, c), 3.0 * s.sigma(e, c)}) {
        line += ",";
        if (observed) {
          AppendNumber(line, v);
        } else {
          line += "nan";
        }
      }
    }
    out << line << "\n";
  }
}

}  // namespace insdiag::cli
