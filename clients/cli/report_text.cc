#include "report_text.h"

#include <charconv>
#include <cstdio>
#include <string>

#include "insdiag/engine/filter/observation.h"

namespace insdiag::cli {
namespace {

std::string Format(const char* fmt, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, fmt, v);
  return buf;
}

void AppendNumber(std::string& line, double v) {
  char buf[32];
  const auto [end, ec] = std::to_chars(buf, buf + sizeof buf, v);
  line.append(buf, ec == std::errc() ? end : buf);
}

}  // namespace

void PrintReport(const engine::AnalysisReport& r, std::ostream& out) {
  out << "verdict: " << engine::VerdictName(r.verdict) << "\n";
  out << "model: base";
  for (const auto& e : r.model_effects) out << " + " << e;
  out << "  (" << r.parameter_count << " parameters)\n";
  out << "run: " << r.samples << " samples over " << Format("%.0f", r.duration_s) << " s at "
      << Format("%.4g", r.sample_rate_hz) << " Hz, updates every " << Format("%.3g", r.update_interval_s) << " s\n";
  out << "NIS mean " << Format("%.4f", r.nis_mean) << " (band " << Format("%.4f", r.nis_band_low) << " … "
      << Format("%.4f", r.nis_band_high) << "), log-likelihood " << Format("%.2f", r.log_likelihood) << ", AIC "
      << Format("%.2f", r.aic) << ", BIC " << Format("%.2f", r.bic) << "\n\n";
  out << "channel   unit   residual RMS   fit %   NIS mean   whiteness p   β²>γ²\n";
  for (const auto& c : r.channels) {
    char line[160];
    std::snprintf(line, sizeof line, "%-8s  %-5s  %12.4g  %6.1f  %9.4f  %12.3g  %5.1f%%\n", c.name.c_str(),
                  c.unit.c_str(), c.rms, c.fit_percent, c.nis_mean, c.whiteness_p_value,
                  100.0 * c.fraction_over_gamma2);
    out << line;
  }
  if (!r.faults.empty()) {
    out << "\nwhere the model fails (γ² = " << Format("%.2f", r.gamma2) << ", η² = " << Format("%.3f", r.eta2)
        << "):\n";
    for (const auto& f : r.faults) {
      out << "  " << engine::FaultKindName(f.kind) << " " << f.channel << " " << Format("%.2f", f.start_s) << " … "
          << Format("%.2f", f.end_s) << " s (peak " << Format("%.3g", f.peak_statistic) << ")\n";
    }
  }
  for (const auto& l : r.localisation) {
    out << "  failed sensor: " << l.state << " jumped by " << Format("%.3g", l.jump) << " ± "
        << Format("%.2g", l.jump_std_error) << " at " << Format("%.1f", l.time_s) << " s (p "
        << Format("%.2g", l.p_value) << ")\n";
  }
  if (!r.discrepancies.empty()) {
    out << "\nforward/backward discrepancies:\n";
    for (const auto& d : r.discrepancies) {
      out << "  " << d.state << " at " << Format("%.1f", d.time_s) << " s: " << Format("%.1f", d.statistic)
          << " (p " << Format("%.2g", d.p_value) << ")\n";
    }
  }
  if (!r.effect_candidates.empty()) {
    out << "\nmissing effects, most significant first:\n";
    int shown = 0;
    for (const auto& c : r.effect_candidates) {
      if (shown++ == 10) break;
      out << "  " << c.name << "  " << (c.identifiable ? "" : "(not identifiable with this profile) ")
          << "estimate " << Format("%.3g", c.estimate) << " ± " << Format("%.2g", c.std_error) << " " << c.unit
          << ", statistic " << Format("%.1f", c.statistic) << ", p " << Format("%.2g", c.p_value_holm)
          << " (Holm), ΔAIC " << Format("%.1f", c.predicted_delta_aic) << "\n";
    }
  }
  if (!r.identified.empty()) {
    out << "\nidentified parameters:\n";
    for (const auto& p : r.identified) {
      out << "  " << p.name << " = " << Format("%.4g", p.value) << " ± " << Format("%.2g", p.std_error) << " "
          << p.unit << " [" << p.method << "]";
      if (p.a_priori == p.a_priori) out << " (a priori " << Format("%.4g", p.a_priori) << ")";
      out << "\n";
    }
  }
  for (const auto& n : r.notes) out << "note: " << n << "\n";
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
      for (double v : {s.measured(e, c), s.predicted(e, c), s.residual(e, c), 3.0 * s.sigma(e, c)}) {
        line += ",";
        AppendNumber(line, v);
      }
    }
    out << line << "\n";
  }
}

}  // namespace insdiag::cli
