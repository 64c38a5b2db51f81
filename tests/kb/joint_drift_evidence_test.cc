// A drift's σ and τ identified together are weighed as one bivariate term
// (kb/src/joint_evidence.h): far from nominal across the likelihood's ridge
// is evidence however wide each marginal is; a healthy drift that wandered
// along the ridge is not. Reports built as the engine reports them, against
// the built-in INS-2000 unit type and failure modes.
#include <absl/strings/match.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>

#include "evidence_reports.h"
#include "insdiag/kb/diagnosis.h"

namespace insdiag::kb {
namespace {

using testing::DiagnoseReport;
using testing::Identified;
using testing::Ins2000;
using testing::Nominal;
using testing::NominalReport;
using testing::TermNamed;

// Sets a drift's σ and τ to `sigma_ratio` and `tau_ratio` × nominal with
// relative standard errors (the SEs of their logs) and the correlation of
// the two estimates' logs, as the likelihood identification reports them.
void SetDrift(v1::AnalysisReport& report, const std::string& drift, double sigma_ratio, double sigma_log_se,
              double tau_ratio, double tau_log_se, double log_correlation) {
  auto* sigma = Identified(report, drift + ".sigma");
  auto* tau = Identified(report, drift + ".tau");
  ASSERT_NE(sigma, nullptr);
  ASSERT_NE(tau, nullptr);
  sigma->set_value(sigma_ratio * Nominal(drift + ".sigma"));
  sigma->set_std_error(sigma_log_se * sigma->value());
  tau->set_value(tau_ratio * Nominal(drift + ".tau"));
  tau->set_std_error(tau_log_se * tau->value());
  for (auto* p : {sigma, tau}) {
    p->set_method(v1::IdentifiedParameter::ML);
    p->set_log_correlation(log_correlation);
  }
  sigma->set_jointly_with(tau->name());
  tau->set_jointly_with(sigma->name());
}

// A drift test of a gyro whose drift σ tripled (τ unchanged), the estimate
// displaced by one standard error along the likelihood's ridge, as a run of
// a few correlation times leaves it: σ 4.9× ± 48 %, τ 2.7× ± 100 %, their
// logs correlated +0.95. Each marginal alone is within three of its errors
// of nominal (τ within one); together they are about four from it.
TEST(JointDriftEvidenceTest, ADriftFarAcrossTheRidgeIsEvidenceThoughEachMarginalIsWide) {
  v1::AnalysisReport joint = NominalReport();
  SetDrift(joint, "gyro_bias_gm.x", 4.9, 0.48, 2.7, 1.0, 0.95);
  const Diagnosis d = DiagnoseReport(joint);
  EXPECT_EQ(d.candidates[0].module, "gyro.x") << ToProto(d).DebugString();
  EXPECT_GT(d.candidates[0].probability, 0.8);

  const auto& f = Ins2000();
  const Evidence e = EvidenceFromReport(FindingsOf(joint), f.unit_type, f.settings);
  const EvidenceTerm* sigma = TermNamed(e, "gyro_bias_gm.x.sigma");
  ASSERT_NE(sigma, nullptr);
  EXPECT_EQ(sigma->jointly_with, "gyro_bias_gm.x.tau");
  EXPECT_TRUE(sigma->significant) << sigma->line;
  EXPECT_THAT(sigma->line, ::testing::HasSubstr("with its τ: χ²₂"));

  // The same marginals weighed as if independent: the ridge's information lost.
  v1::AnalysisReport apart = joint;
  for (auto& p : *apart.mutable_identified()) {
    p.clear_log_correlation();
    p.clear_jointly_with();
  }
  const Evidence separate = EvidenceFromReport(FindingsOf(apart), f.unit_type, f.settings);
  const EvidenceTerm* separate_sigma = TermNamed(separate, "gyro_bias_gm.x.sigma");
  ASSERT_NE(separate_sigma, nullptr);
  EXPECT_TRUE(separate_sigma->jointly_with.empty());
  double apart_probability = 0.0;
  const Diagnosis apart_diagnosis = DiagnoseReport(apart);
  for (const auto& c : apart_diagnosis.candidates) {
    if (c.module == "gyro.x") apart_probability = c.probability;
  }
  EXPECT_LT(apart_probability, d.candidates[0].probability - 0.3);
}

// Healthy drifts scattered by the measurement along a tight ridge
// (correlation +0.99, marginal errors 50 % and 100 %): drawn from the joint
// distribution a healthy unit has, x ~ N(0, diag(s_h²) + M). The ranking
// must stay healthy and the drift test's false-alarm rate at its level.
// 400 draws: a true healthy-first rate of 90 % passes the 95 % bar with
// probability below 10⁻³; a false-alarm rate of 4 % (four times the
// level) passes the bound of 2.5 % with probability below 0.04.
TEST(JointDriftEvidenceTest, HealthyDriftsWanderingAlongTheRidgeStayHealthyAtTheTestsLevel) {
  const auto& f = Ins2000();
  const double level = f.settings.significance_level;
  std::mt19937_64 rng(20261207);
  std::normal_distribution<double> unit(0.0, 1.0);
  constexpr int kDraws = 400;
  constexpr double kRho = 0.99, kSigmaLogSe = 0.5, kTauLogSe = 1.0;
  int healthy_first = 0, false_alarms = 0;
  for (int i = 0; i < kDraws; ++i) {
    v1::AnalysisReport report = NominalReport();
    SetDrift(report, "gyro_bias_gm.y", 1.0, kSigmaLogSe, 1.0, kTauLogSe, kRho);
    const Evidence nominal = EvidenceFromReport(FindingsOf(report), f.unit_type, f.settings);
    const EvidenceTerm* nominal_sigma = TermNamed(nominal, "gyro_bias_gm.y.sigma");
    const EvidenceTerm* nominal_tau = TermNamed(nominal, "gyro_bias_gm.y.tau");
    ASSERT_NE(nominal_sigma, nullptr);
    ASSERT_NE(nominal_tau, nullptr);
    const double hs = nominal_sigma->healthy_sd, ht = nominal_tau->healthy_sd;
    // Measurement errors along the ridge plus independent healthy scatter.
    const double z1 = unit(rng), z2 = unit(rng);
    const double ms = kSigmaLogSe * z1;
    const double mt = kTauLogSe * (kRho * z1 + std::sqrt(1.0 - kRho * kRho) * z2);
    const double xs = ms + hs * unit(rng), xt = mt + ht * unit(rng);
    // The reported SE is relative to the reported value: set it so that the
    // SE of the log is the stated one.
    SetDrift(report, "gyro_bias_gm.y", std::exp(xs), kSigmaLogSe, std::exp(xt), kTauLogSe, kRho);
    const Evidence e = EvidenceFromReport(FindingsOf(report), f.unit_type, f.settings);
    const EvidenceTerm* sigma = TermNamed(e, "gyro_bias_gm.y.sigma");
    ASSERT_NE(sigma, nullptr);
    false_alarms += sigma->significant ? 1 : 0;
    healthy_first += DiagnoseReport(report).candidates[0].module == "healthy" ? 1 : 0;
  }
  EXPECT_GE(healthy_first, 0.95 * kDraws) << healthy_first << " of " << kDraws;
  EXPECT_LE(false_alarms, 2.5 * level * kDraws) << false_alarms << " of " << kDraws;
}

// Each single-sensor drift change has a mode that names its sensor: σ up
// (wear), τ up (a lengthened thermal path), the white noise up (pick-off or
// servo electronics), measured as a long drift test measures them.
TEST(JointDriftEvidenceTest, EachDriftChangeOnOneSensorNamesThatSensor) {
  {
    v1::AnalysisReport r = NominalReport();
    SetDrift(r, "gyro_bias_gm.z", 1.0, 0.3, 10.0, 0.35, 0.7);
    const Diagnosis d = DiagnoseReport(r);
    EXPECT_EQ(d.candidates[0].module, "gyro.z") << ToProto(d).DebugString();
    EXPECT_EQ(d.candidates[0].failure_mode, "failureModes/dtg-thermal-path-loss.z");
  }
  {
    v1::AnalysisReport r = NominalReport();
    SetDrift(r, "acc_bias_gm.y", 3.0, 0.35, 1.0, 0.6, 0.98);
    EXPECT_EQ(DiagnoseReport(r).candidates[0].module, "acc.y") << ToProto(DiagnoseReport(r)).DebugString();
  }
  for (const auto& [name, module, mode] :
       {std::tuple{"gyro_arw.x", "gyro.x", "failureModes/dtg-pickoff-noise.x"},
        std::tuple{"acc_vrw.z", "acc.z", "failureModes/acc-servo-noise.z"}}) {
    v1::AnalysisReport r = NominalReport();
    auto* p = Identified(r, name);
    p->set_value(2.0 * Nominal(name));
    p->set_std_error(0.01 * p->value());
    const Diagnosis d = DiagnoseReport(r);
    EXPECT_EQ(d.candidates[0].module, module) << ToProto(d).DebugString();
    EXPECT_EQ(d.candidates[0].failure_mode, mode);
  }
}

}  // namespace
}  // namespace insdiag::kb
