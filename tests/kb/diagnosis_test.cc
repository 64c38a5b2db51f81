// The diagnosis as a pure function: evidence built in the test (identified
// parameters and effect candidates as the engine reports them) against the
// built-in INS-2000 unit type and failure modes.
#include "insdiag/kb/diagnosis.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <set>

#include "evidence_reports.h"

namespace insdiag::kb {
namespace {

using testing::Ins2000;
using testing::NominalReport;
using testing::Identified;
using testing::Candidate;
using testing::Nominal;
using testing::Tolerance;

using ::testing::HasSubstr;

v1::Diagnosis DiagnoseReport(const v1::AnalysisReport& report, PriorInputs prior = {}) {
  const auto& f = Ins2000();
  return Diagnose(EvidenceFromReport(report, f.unit_type, f.catalogue.settings()), f.modes, f.catalogue.settings(),
                  prior);
}

double ProbabilityOf(const v1::Diagnosis& d, const std::string& mode) {
  for (const auto& h : d.hypotheses()) {
    if (h.failure_mode() == mode) return h.probability();
  }
  return 0.0;
}

TEST(FailureModeCatalogueTest, Ins2000HasSixteenArguedModesWhoseTermsTheUnitTypeOrTheEngineNames) {
  const auto& f = Ins2000();
  EXPECT_EQ(f.catalogue.modes_size(), 16);
  std::set<std::string> roles;
  std::set<std::string> nominal;
  for (const auto& p : f.unit_type.nominal()) nominal.insert(p.name());
  for (const auto& m : f.modes) {
    roles.insert(m.module_role());
    EXPECT_GT(m.description().size(), 100u) << m.name() << ": argue the physics";
    for (const auto& s : m.signature()) {
      if (s.scale() == "z") continue;  // structure effects: standard scores, no nominal needed
      const std::string family = s.parameter().substr(0, s.parameter().find('.'));
      bool known = nominal.contains(s.parameter());
      for (const auto& n : nominal) known = known || (s.parameter().ends_with(".*") && n.rfind(family + ".", 0) == 0);
      if (family.find("quantization") != std::string::npos) continue;  // INS-2000 has no nominal quantisation yet
      EXPECT_TRUE(known) << m.name() << ": " << s.parameter() << " has no nominal value in INS-2000";
    }
  }
  EXPECT_EQ(roles, (std::set<std::string>{"gyro.x", "gyro.y", "gyro.z", "acc.x", "acc.y", "acc.z", "interface_card",
                                          "control_card", "coupler", "power_supply"}));
}

TEST(DiagnosisTest, HealthyUnitsTopHypothesisIsHealthy) {
  const v1::Diagnosis d = DiagnoseReport(NominalReport());
  ASSERT_GT(d.candidates_size(), 0);
  EXPECT_EQ(d.candidates(0).module(), "healthy");
  EXPECT_GT(d.candidates(0).probability(), 0.5);
}

TEST(DiagnosisTest, TripledGyroXDriftSigmaPointsAtGyroX) {
  v1::AnalysisReport report = NominalReport();
  auto* sigma = Identified(report, "gyro_bias_gm.x.sigma");
  ASSERT_NE(sigma, nullptr);
  sigma->set_value(3.0 * Nominal("gyro_bias_gm.x.sigma"));
  sigma->set_std_error(0.12 * sigma->value());
  const v1::Diagnosis d = DiagnoseReport(report);
  ASSERT_GT(d.candidates_size(), 0);
  EXPECT_EQ(d.candidates(0).module(), "gyro.x") << d.DebugString();
  EXPECT_EQ(d.candidates(0).failure_mode(), "failureModes/dtg-bearing-wear.x");
  EXPECT_THAT(d.candidates(0).evidence(), ::testing::Contains(HasSubstr("3× nominal")));
}

TEST(DiagnosisTest, CommonGyroScaleFactorShiftPointsAtTheInterfaceCard) {
  v1::AnalysisReport report = NominalReport();
  for (const char* axis : {"x", "y", "z"}) {
    const std::string name = std::string("gyro_scale_factor.") + axis;
    auto* c = Candidate(report, name);
    ASSERT_NE(c, nullptr);
    c->set_estimate(4.0 * Tolerance(name));  // ≈ +200 ppm on every axis
    c->set_std_error(0.2 * Tolerance(name));
    c->set_p_value(1e-12);
    c->set_p_value_holm(1e-10);
  }
  const v1::Diagnosis d = DiagnoseReport(report);
  ASSERT_GT(d.candidates_size(), 0);
  EXPECT_EQ(d.candidates(0).module(), "interface_card") << d.DebugString();
  EXPECT_THAT(d.candidates(0).evidence(), ::testing::Contains(HasSubstr("all positive, significant")));
}

TEST(DiagnosisTest, OneAxisScaleFactorShiftPointsAtThatGyroNotTheInterfaceCard) {
  v1::AnalysisReport report = NominalReport();
  auto* c = Candidate(report, "gyro_scale_factor.y");
  c->set_estimate(5.0 * Tolerance("gyro_scale_factor.y"));
  c->set_std_error(0.2 * Tolerance("gyro_scale_factor.y"));
  c->set_p_value_holm(1e-10);
  const v1::Diagnosis d = DiagnoseReport(report);
  EXPECT_EQ(d.candidates(0).module(), "gyro.y") << d.DebugString();
  EXPECT_EQ(d.candidates(0).failure_mode(), "failureModes/dtg-torquer-scale-shift.y");
}

TEST(DiagnosisTest, ArwUpOnAllGyrosAndVrwUpOnAllAccelerometersPointsAtThePowerSupply) {
  v1::AnalysisReport report = NominalReport();
  for (const char* axis : {"x", "y", "z"}) {
    for (const std::string family : {"gyro_arw.", "acc_vrw."}) {
      auto* p = Identified(report, family + axis);
      p->set_value(2.0 * Nominal(family + axis));
      p->set_std_error(0.1 * p->value());
    }
  }
  EXPECT_EQ(DiagnoseReport(report).candidates(0).module(), "power_supply");
}

TEST(DiagnosisTest, EvidenceNoModeExplainsGoesToUnknown) {
  v1::AnalysisReport report = NominalReport();
  // A drift correlation time 20× nominal with its σ unchanged: no mode predicts it.
  auto* tau = Identified(report, "gyro_bias_gm.z.tau");
  tau->set_value(20.0 * Nominal("gyro_bias_gm.z.tau"));
  tau->set_std_error(0.1 * tau->value());
  EXPECT_EQ(DiagnoseReport(report).candidates(0).module(), "unknown") << DiagnoseReport(report).DebugString();
}

// The engine lists every random structure the model lacks: one no test
// measured is no evidence, and one below its test's screen (no standard
// error) weighs as the z of its p-value, not as √χ² on three degrees of freedom.
TEST(DiagnosisTest, UntestedStructuresAreNoEvidenceAndScreenedOnesWeighByTheirPValue) {
  v1::AnalysisReport report = NominalReport();
  auto* untested = report.add_effect_candidates();
  untested->set_name("gyro_bias_second_order.x");
  untested->set_family("gyro_bias_second_order");
  untested->set_source("LIKELIHOOD");
  untested->set_degrees_of_freedom(3);
  untested->set_p_value(1.0);
  untested->set_p_value_holm(1.0);
  untested->set_identifiable(true);
  untested->set_not_tested(true);
  auto* screened = report.add_effect_candidates();
  screened->set_name("gyro_bias_second_order.y");
  screened->set_family("gyro_bias_second_order");
  screened->set_source("LIKELIHOOD");
  screened->set_degrees_of_freedom(3);
  screened->set_statistic(5.07);
  screened->set_estimate(7e-8);
  screened->set_p_value(0.5);
  screened->set_p_value_holm(1.0);
  screened->set_identifiable(true);
  const auto& f = Ins2000();
  const Evidence evidence = EvidenceFromReport(report, f.unit_type, f.catalogue.settings());
  const EvidenceTerm* x = nullptr;
  const EvidenceTerm* y = nullptr;
  for (const EvidenceTerm& t : evidence.terms) {
    if (t.name == "gyro_bias_second_order.x") x = &t;
    if (t.name == "gyro_bias_second_order.y") y = &t;
  }
  EXPECT_EQ(x, nullptr) << "an untested candidate counted as evidence";
  ASSERT_NE(y, nullptr);
  EXPECT_EQ(y->scale, Scale::kZ);
  EXPECT_NEAR(y->x, 0.6745, 1e-3);  // Φ⁻¹(1 − 0.5/2)
}

TEST(DiagnosisTest, ReportWithoutEvidenceIsHealthyWhenGoodAndUnknownOtherwise) {
  v1::AnalysisReport report;
  report.set_verdict(v1::AnalysisReport::GOOD);
  v1::Diagnosis d = DiagnoseReport(report);
  EXPECT_EQ(d.candidates(0).module(), "healthy");
  EXPECT_THAT(d.notes(), ::testing::Contains(HasSubstr("no identified parameters")));
  report.set_verdict(v1::AnalysisReport::FAULTY);
  d = DiagnoseReport(report);
  EXPECT_EQ(d.candidates(0).module(), "unknown");
  EXPECT_NEAR(d.candidates(0).probability(), 1.0, 1e-9);
}

TEST(DiagnosisTest, ConfirmedFailuresRaiseTheModesPriorAndProbability) {
  v1::AnalysisReport report = NominalReport();
  auto* sigma = Identified(report, "gyro_bias_gm.y.sigma");
  sigma->set_value(1.8 * Nominal("gyro_bias_gm.y.sigma"));  // ambiguous: between healthy and worn
  sigma->set_std_error(0.12 * sigma->value());
  PriorInputs prior;
  prior.fleet_exposure_hours = 2e6;
  const double before = ProbabilityOf(DiagnoseReport(report, prior), "failureModes/dtg-bearing-wear.y");
  prior.confirmed_failures["failureModes/dtg-bearing-wear.y"] = 40;
  const double after = ProbabilityOf(DiagnoseReport(report, prior), "failureModes/dtg-bearing-wear.y");
  EXPECT_GT(after, 1.5 * before) << before << " → " << after;
}

TEST(DiagnosisTest, ModeProbabilitiesSumToOneAndModulesSumTheirModes) {
  v1::AnalysisReport report = NominalReport();
  Identified(report, "acc_bias_gm.z.sigma")->set_value(2.5 * Nominal("acc_bias_gm.z.sigma"));
  const v1::Diagnosis d = DiagnoseReport(report);
  double total = 0.0, modules = 0.0;
  for (const auto& h : d.hypotheses()) total += h.probability();
  for (const auto& c : d.candidates()) modules += c.probability();
  EXPECT_NEAR(total, 1.0, 1e-9);
  EXPECT_NEAR(modules, 1.0, 1e-9);
  EXPECT_EQ(d.candidates(0).module(), "acc.z") << d.DebugString();
}

TEST(RefineSignatureTest, ConfirmedCasesPullTheExpectedChangeTowardsThemWithTheExpertAsPrior) {
  v1::Signature term;
  term.set_parameter("gyro_bias_gm.x.sigma");
  term.set_direction(v1::Signature::UP);
  term.set_scale("log_ratio");
  term.set_expert_change(1.0);
  term.set_expert_spread(0.45);
  v1::DiagnosisSettings settings;
  settings.set_expert_signature_weight(3);
  const std::vector<double> cases = {1.6, 1.5, 1.7};
  const v1::Signature refined = RefineSignature(term, cases, settings);
  // μ = (3·1.0 + 3·1.6)/6 = 1.3
  EXPECT_NEAR(refined.change(), 1.3, 1e-12);
  EXPECT_EQ(refined.confirmed_cases(), 3);
  // s² = (3·0.45² + 0.02 + 3·3·0.36/6)/6
  EXPECT_NEAR(refined.spread(), std::sqrt((3 * 0.2025 + 0.02 + 0.54) / 6.0), 1e-12);
  EXPECT_EQ(RefineSignature(term, {}, settings).change(), 1.0);
}

}  // namespace
}  // namespace insdiag::kb
