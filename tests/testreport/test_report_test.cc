// The test report built from an analysis's messages: what it states (the
// verdict, the tolerances, identified values against nominal with their
// intervals, the effects, the diagnosis, the plots), HTML that is
// self-contained and escaped, and a PDF that poppler renders and reads back.
#include "insdiag/testreport/test_report.h"

#include <absl/strings/match.h>
#include <gmock/gmock.h>
#include <google/protobuf/text_format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

#include "support/pdf_check.h"
#include "support/subprocess.h"

namespace insdiag::testreport {
namespace {

using ::testing::HasSubstr;
using ::testing::Not;

template <typename Message>
Message Parse(const std::string& text) {
  Message m;
  EXPECT_TRUE(google::protobuf::TextFormat::ParseFromString(text, &m)) << text;
  return m;
}

// A faulty unit whose analysis added a scale factor and found a bias step;
// one parameter is outside its tolerance and one name carries markup.
TestReportInput FaultyUnit() {
  TestReportInput in;
  in.analysis = Parse<v1::Analysis>(R"pb(
    name: "analyses/0f0e" run: "runs/7a7b" state: SUCCEEDED unit: "units/SN-42" discover: true
    report {
      verdict: FAULTY
      model { effects: "gyro_scale_factor.z" }
      nis_mean: 1.8 nis_band_low: 0.97 nis_band_high: 1.03 gamma2: 5.2426 eta2: 1.6
      channels { name: "vel_n" rms: 0.0021 unit: "m/s" fit_percent: 97.5 nis_mean: 1.9 fraction_over_gamma2: 0.031 }
      fault_intervals { channel: "vel_n" start_s: 1500 end_s: 3000 kind: ABRUPT peak_statistic: 88 }
      identified { name: "gyro_bias_gm.x.sigma" value: 2.0e-7 std_error: 1.0e-8 method: ML unit: "rad/s" }
      identified { name: "gyro_scale_factor.z" value: 1.02e-4 std_error: 2.0e-6 method: FILTER a_priori: 0 }
      identified { name: "odd<b>&\"name\"" value: 1 std_error: 0.5 method: FILTER }
      effect_candidates { name: "gyro_bias_step.x" estimate: 2.9e-6 std_error: 1e-7 p_value_holm: 1e-12
                          source: "GLR" unit: "rad/s" onset_s: 1500.5 }
      effect_candidates { name: "acc_scale_factor.y" estimate: 1e-6 std_error: 1e-6 p_value_holm: 0.8 source: "SCORE" }
      localisation { state: "gyro_bias_gm.x" time_s: 1500 method: "GLR" p_value: 1e-9 }
      discovery { step: 1 effect: "gyro_scale_factor.z" estimate: 1.02e-4 std_error: 2e-6 p_value: 1e-20 }
      allan { channel: "gyro_x" unit: "rad/s" tau_s: [0.1, 1, 10, 100] deviation: [1e-5, 3e-6, 1e-6, 5e-7]
              fitted: [1.1e-5, 3.2e-6, 1e-6, 4e-7] }
      notes: "a note of the engine"
    })pb");
  in.run = Parse<v1::Run>(R"pb(
    name: "runs/7a7b" sample_count: 36000 duration_s: 3600 sha256: "ab12"
    metadata { unit_serial: "SN-42" unit_type: "INS-2000" site { latitude_deg: 55.7 longitude_deg: 37.6 height_m: 150 }
               extra { key: "operator" value: "J. Smith <QA>" } })pb");
  in.unit_type = Parse<v1::UnitType>(R"pb(
    name: "unitTypes/INS-2000" display_name: "INS-2000"
    nominal { name: "gyro_bias_gm.x.sigma" value: 4.85e-8 tolerance: 4.85e-8 unit: "rad/s" }
    nominal { name: "gyro_scale_factor.z" value: 0 tolerance: 2e-4 })pb");
  in.diagnosis = Parse<v1::Diagnosis>(R"pb(
    name: "diagnoses/d1" analysis: "analyses/0f0e"
    candidates { module: "gyro.x" failure_mode: "failureModes/dtg-rotor-shift.x" probability: 0.91
                 evidence: "gyro_bias_step.x: z = 29" }
    candidates { module: "healthy" probability: 0.01 })pb");
  v1::ChannelEnvelope& e = *in.residuals.add_channels();
  e.set_channel("vel_n");
  for (int i = 0; i < 200; ++i) {
    const double t = 18.0 * i;
    e.add_t(t);
    e.add_residual_min(0.002 * std::sin(t / 300) - 0.0005);
    e.add_residual_max(0.002 * std::sin(t / 300) + 0.0005);
    e.add_sigma3_max(0.004);
  }
  in.generated_at = "2026-01-26T09:30:00Z";
  return in;
}

TEST(TestReport, StatesTheVerdictToleranceIntervalsNominalEffectsAndDiagnosis) {
  const std::string html = RenderHtml(BuildTestReport(FaultyUnit()));
  EXPECT_THAT(html, HasSubstr("Verdict: FAULTY"));
  EXPECT_THAT(html, HasSubstr("γ² = 5.243"));
  EXPECT_THAT(html, HasSubstr("[0.97, 1.03]"));  // the NIS band
  // 2e-7 ± 1.96 × 1e-8, beside the nominal value and outside the tolerance.
  EXPECT_THAT(html, HasSubstr("[1.804e-07, 2.196e-07]"));
  EXPECT_THAT(html, HasSubstr("<td>4.85e-08</td>"));
  EXPECT_THAT(html, HasSubstr("outside tolerance"));
  EXPECT_THAT(html, HasSubstr("within tolerance"));  // the scale factor, 1.02e-4 of 2e-4
  EXPECT_THAT(html, HasSubstr("gyro_scale_factor.z"));
  EXPECT_THAT(html, HasSubstr("gyro_bias_step.x"));  // significant, with its onset
  EXPECT_THAT(html, HasSubstr("1500"));
  EXPECT_THAT(html, Not(HasSubstr("acc_scale_factor.y")));  // Holm p 0.8 is no finding
  EXPECT_THAT(html, HasSubstr("failureModes/dtg-rotor-shift.x"));
  EXPECT_THAT(html, HasSubstr("91.0 %"));
  EXPECT_THAT(html, HasSubstr("a note of the engine"));
}

// Each identified constant says whether the run tells it; those it cannot are
// named under the table with why.
TEST(TestReport, SaysWhichIdentifiedParametersTheRunCannotTell) {
  TestReportInput in = FaultyUnit();
  auto* report = in.analysis.mutable_report();
  for (auto& p : *report->mutable_identified()) {
    if (p.name() == "gyro_scale_factor.z") {
      p.set_observability(v1::IdentifiedParameter::OBSERVABLE);
    } else if (p.name() == "odd<b>&\"name\"") {
      p.set_observability(v1::IdentifiedParameter::INSEPARABLE);
      p.set_observability_note("only with acc_turn_on_bias.z (correlation +1.000)");
    }
  }
  const std::string html = RenderHtml(BuildTestReport(in));
  EXPECT_THAT(html, HasSubstr("<th>observability</th>"));
  EXPECT_THAT(html, HasSubstr("<td>observable</td>"));
  EXPECT_THAT(html, HasSubstr("<td>inseparable</td>"));
  EXPECT_THAT(
      html,
      HasSubstr(
          "Not observable in this run: odd&lt;b&gt;&amp;&quot;name&quot; (inseparable: only with "
          "acc_turn_on_bias.z (correlation +1.000))"));
  // The ML drift was not judged (not a filter constant): a dash, and no sentence about it.
  EXPECT_THAT(html, Not(HasSubstr("gyro_bias_gm.x.sigma (")));
  const std::string without = RenderHtml(BuildTestReport(FaultyUnit()));
  EXPECT_THAT(without, Not(HasSubstr("Not observable in this run")));
}

TEST(TestReport, HtmlIsSelfContainedAndEscapesEveryText) {
  const std::string html = RenderHtml(BuildTestReport(FaultyUnit()));
  EXPECT_TRUE(absl::StartsWith(html, "<!DOCTYPE html>"));
  EXPECT_THAT(html, HasSubstr("<style>"));
  EXPECT_THAT(html, HasSubstr("<svg"));  // the plots, inline
  EXPECT_THAT(html, HasSubstr("<polyline"));
  for (const char* external : {"<script", "<link", "<img", "src=", "href=", "url(", "@import"}) {
    EXPECT_THAT(html, Not(HasSubstr(external))) << external;
  }
  // The only URLs are the SVG namespace's name, which nothing fetches.
  int urls = 0, svgs = 0;
  for (auto at = html.find("http"); at != std::string::npos; at = html.find("http", at + 1), ++urls) {
    EXPECT_EQ(html.compare(at, 26, "http://www.w3.org/2000/svg"), 0) << html.substr(at, 40);
  }
  for (auto at = html.find("<svg "); at != std::string::npos; at = html.find("<svg ", at + 1)) ++svgs;
  EXPECT_EQ(svgs, 2);  // the residual and the Allan deviation
  EXPECT_EQ(urls, svgs);
  EXPECT_THAT(html, HasSubstr("odd&lt;b&gt;&amp;&quot;name&quot;"));
  EXPECT_THAT(html, HasSubstr("J. Smith &lt;QA&gt;"));
  EXPECT_THAT(html, Not(HasSubstr("<b>")));
  EXPECT_THAT(html, Not(HasSubstr("<QA>")));
}

TEST(TestReport, WithoutDiagnosisOrUnitTypeItSaysSo) {
  TestReportInput in = FaultyUnit();
  in.diagnosis.reset();
  in.unit_type.reset();
  const std::string html = RenderHtml(BuildTestReport(in));
  EXPECT_THAT(html, HasSubstr("No diagnosis has been made of this analysis."));
  EXPECT_THAT(html, HasSubstr("0 (a priori)"));  // the scale factor's a-priori value stands in
  EXPECT_THAT(html, HasSubstr("no tolerance"));
}

TEST(TestReport, PdfRendersAndReadsBackWithTheVerdictAndTheEffect) {
  const Document document = BuildTestReport(FaultyUnit());
  const std::string pdf = RenderPdf(document);
  ASSERT_TRUE(testing::CheckPdfStructure(pdf).ok()) << testing::CheckPdfStructure(pdf);
  // Kept for a reader's eyes, as the page's screenshots are.
  std::filesystem::create_directories(INSDIAG_ARTIFACTS_DIR);
  std::ofstream(std::filesystem::path(INSDIAG_ARTIFACTS_DIR) / "faulty-unit.pdf", std::ios::binary) << pdf;
  std::ofstream(std::filesystem::path(INSDIAG_ARTIFACTS_DIR) / "faulty-unit.html") << RenderHtml(document);
  const std::filesystem::path dir = testing::MakeTempDir("insdiag-test-report");
  auto rendered = testing::RenderBack(pdf, dir);
  if (absl::IsUnavailable(rendered.status())) GTEST_SKIP() << rendered.status().message();
  ASSERT_TRUE(rendered.ok()) << rendered.status();
  ASSERT_GE(rendered->ink_fraction.size(), 2u);
  for (const double ink : rendered->ink_fraction) EXPECT_GT(ink, 0.002);
  EXPECT_THAT(rendered->text, HasSubstr("Verdict: FAULTY"));
  EXPECT_THAT(rendered->text, HasSubstr("gyro_scale_factor.z"));
  EXPECT_THAT(rendered->text, HasSubstr("gyro_bias_step.x"));
  EXPECT_THAT(rendered->text, HasSubstr("gamma² = 5.243"));  // WinAnsi lacks γ: spelled out
  EXPECT_THAT(rendered->text, HasSubstr("odd<b>&\"name\""));   // PDF text needs no markup escaping
  EXPECT_THAT(rendered->text, HasSubstr("page 1 of"));
  EXPECT_THAT(rendered->text, HasSubstr("vel_n: residual"));  // the plot's title
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace insdiag::testreport
