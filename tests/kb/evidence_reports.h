// Analysis reports as the engine reports them, built in tests: the
// INS-2000 unit type's parameters at nominal with realistic standard errors,
// and helpers to move one of them.
#pragma once

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "insdiag/engine/status_macros.h"
#include "insdiag/kb/catalogue_data.h"
#include "insdiag/kb/diagnose_analysis.h"
#include "insdiag/kb/diagnosis.h"
#include "insdiag/kb/failure_mode_catalogue.h"
#include "insdiag/kb/knowledge_messages.h"

namespace insdiag::kb::testing {

struct Fixture {
  UnitType unit_type;
  v1::FailureModeCatalogue catalogue;  // as the experts write it
  DiagnosisSettings settings;
  std::vector<FailureMode> modes;
};

inline const Fixture& Ins2000() {
  static const Fixture f = [] {
    Fixture out;
    auto built_in = BuiltinUnitTypeCatalogue("INS-2000");
    EXPECT_TRUE(built_in.ok()) << built_in.status();
    out.unit_type = built_in->unit_type;
    out.settings = built_in->settings;
    out.modes = built_in->failure_modes;
    auto catalogue = BuiltinFailureModeCatalogue("INS-2000");
    EXPECT_TRUE(catalogue.ok()) << catalogue.status();
    out.catalogue = **catalogue;
    return out;
  }();
  return f;
}

inline double Nominal(const std::string& name) {
  for (const NominalParameter& p : Ins2000().unit_type.nominal) {
    if (p.name == name) return p.value;
  }
  ADD_FAILURE() << "no nominal " << name;
  return 0.0;
}

inline double Tolerance(const std::string& name) {
  for (const NominalParameter& p : Ins2000().unit_type.nominal) {
    if (p.name == name) return p.tolerance;
  }
  ADD_FAILURE() << "no tolerance " << name;
  return 1.0;
}

// A report whose identified base-model parameters sit at nominal with
// realistic relative standard errors (σ, τ by ACF; ARW, VRW by Allan), and
// whose identifiable effect candidates are all absent (estimate ≈ 0).
inline v1::AnalysisReport NominalReport() {
  v1::AnalysisReport report;
  report.set_verdict(v1::AnalysisReport::GOOD);
  for (const NominalParameter& p : Ins2000().unit_type.nominal) {
    if (p.value > 0) {
      auto* id = report.add_identified();
      id->set_name(p.name);
      id->set_value(p.value);
      const bool tau = p.name.find(".tau") != std::string::npos;
      id->set_std_error(p.value * (tau ? 0.3 : 0.12));
      id->set_method(p.name.find("_gm") != std::string::npos ? v1::IdentifiedParameter::ACF
                                                             : v1::IdentifiedParameter::ALLAN);
      id->set_unit(p.unit);
    } else {
      auto* c = report.add_effect_candidates();
      c->set_name(p.name);
      c->set_family(p.name.substr(0, p.name.find('.')));
      c->set_estimate(0.05 * p.tolerance);
      c->set_std_error(0.1 * p.tolerance);
      c->set_p_value(0.6);
      c->set_p_value_holm(1.0);
      c->set_identifiable(true);
      c->set_unit(p.unit);
      c->set_source("SCORE");
    }
  }
  return report;
}

inline v1::IdentifiedParameter* Identified(v1::AnalysisReport& r, const std::string& name) {
  for (auto& p : *r.mutable_identified()) {
    if (p.name() == name) return &p;
  }
  return nullptr;
}

// The report's evidence against INS-2000's nominal values.
inline Evidence EvidenceOf(const v1::AnalysisReport& report) {
  const auto& f = Ins2000();
  return EvidenceFromReport(FindingsOf(report), f.unit_type, f.settings);
}

// The report diagnosed against INS-2000's built-in modes with `prior`.
inline Diagnosis DiagnoseReport(const v1::AnalysisReport& report, PriorInputs prior = {}) {
  const auto& f = Ins2000();
  return Diagnose(EvidenceOf(report), f.modes, f.settings, prior);
}

// An analysis diagnosed and stored by `store`, as the API shows the diagnosis.
inline absl::StatusOr<v1::Diagnosis> DiagnoseStored(DiagnosisStore& store, const std::string& analysis) {
  INSDIAG_ASSIGN_OR_RETURN(const StoredDiagnosis stored, AnalysisDiagnoser(store, EncodeDiagnosis).Diagnose(analysis));
  return DecodeDiagnosis(stored);
}

// The evidence term named `name`, or nullptr.
inline const EvidenceTerm* TermNamed(const Evidence& evidence, const std::string& name) {
  for (const EvidenceTerm& t : evidence.terms) {
    if (t.name == name) return &t;
  }
  return nullptr;
}

inline v1::EffectCandidate* Candidate(v1::AnalysisReport& r, const std::string& name) {
  for (auto& c : *r.mutable_effect_candidates()) {
    if (c.name() == name) return &c;
  }
  return nullptr;
}


}  // namespace insdiag::kb::testing
