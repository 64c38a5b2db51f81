// The knowledge base on a real PostgreSQL: seeding, diagnosis of stored
// analyses, resolution into failure records and its effect on later
// diagnoses, fleet statistics over what was written.
#include <absl/strings/escaping.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <bit>
#include <cstdint>

#include "analysis_codec.h"
#include "evidence_reports.h"
#include "insdiag/kb/analysis_store.h"
#include "insdiag/kb/catalogue_data.h"
#include "insdiag/kb/catalogue_store.h"
#include "insdiag/kb/diagnose_analysis.h"
#include "insdiag/kb/diagnosis.h"
#include "insdiag/kb/diagnosis_store.h"
#include "insdiag/kb/failure_record_store.h"
#include "insdiag/kb/fleet_store.h"
#include "insdiag/kb/run_store.h"
#include "support/database_fixture.h"
#include "support/synthetic_run.h"

namespace insdiag::kb {
namespace {

using namespace std::chrono_literals;

std::string NameOf(const FailureRecord& record) { return record.name; }
std::string NameOf(const StoredDiagnosis& diagnosis) { return diagnosis.name; }

class KnowledgeBaseTest : public insdiag::testing::DatabaseTest {
 protected:
  // An analysis diagnosed and stored, as the API shows the diagnosis.
  absl::StatusOr<v1::Diagnosis> Diagnose(const std::string& analysis) {
    return testing::DiagnoseStored(*diagnoses_, analysis);
  }

  void SetUp() override {
    DatabaseTest::SetUp();
    if (IsSkipped() || HasFatalFailure()) return;
    catalogue_ = std::make_unique<CatalogueStore>(pool());
    records_ = std::make_unique<FailureRecordStore>(pool(), DecodeReportFindings);
    diagnoses_ = std::make_unique<DiagnosisStore>(pool(), DecodeReportFindings);
    ASSERT_TRUE(SeedBuiltinCatalogues(*catalogue_).ok());
    ASSERT_TRUE(SeedBuiltinCatalogues(*catalogue_).ok()) << "seeding twice is harmless";
  }

  // A SUCCEEDED analysis of unit `serial` with `report`.
  std::string StoreAnalysis(const std::string& serial, const v1::AnalysisReport& report,
                            const std::string& unit_type = "INS-2000") {
    RunStore runs(pool());
    engine::BenchRun run = insdiag::testing::SyntheticStaticRun(20, 10.0, 3);
    run.metadata.unit_serial = serial;
    run.metadata.unit_type = unit_type;
    auto stored = runs.Create(run, {.sha256 = "x", .request_id = "", .request_fingerprint = ""});
    EXPECT_TRUE(stored.ok()) << stored.status();
    AnalysisStore analyses(pool());
    auto a = analyses.Create(stored->id, server::EncodedSpec(v1::AnalysisSpec()), "");
    auto job = analyses.Claim("t", 30s);
    EXPECT_TRUE(job.ok() && job->has_value());
    EXPECT_TRUE(
        analyses.Complete((*job)->analysis_id, "t", server::EncodedReport(report), server::ReportRowsOf(report), nullptr)
            .ok());
    return a->name;
  }

  static v1::AnalysisReport WornGyroX() {
    v1::AnalysisReport report = testing::NominalReport();
    auto* sigma = testing::Identified(report, "gyro_bias_gm.x.sigma");
    sigma->set_value(3.0 * testing::Nominal("gyro_bias_gm.x.sigma"));
    sigma->set_std_error(0.12 * sigma->value());
    return report;
  }

  static double P(const v1::Diagnosis& d, const std::string& mode) {
    for (const auto& h : d.hypotheses()) {
      if (h.failure_mode() == mode) return h.probability();
    }
    return 0.0;
  }

  std::unique_ptr<CatalogueStore> catalogue_;
  std::unique_ptr<FailureRecordStore> records_;
  std::unique_ptr<DiagnosisStore> diagnoses_;
};

TEST_F(KnowledgeBaseTest, SeedsTheUnitTypeAndItsFailureModes) {
  auto type = catalogue_->GetUnitType("unitTypes/INS-2000");
  ASSERT_TRUE(type.ok()) << type.status();
  EXPECT_GT(type->nominal.size(), 50u);
  auto modes = catalogue_->ListFailureModes("unitTypes/INS-2000", "");
  ASSERT_TRUE(modes.ok());
  EXPECT_EQ(modes->size(), 50u);  // 15 per-axis modes × 3 axes + 5 unit-level modes
  auto card = catalogue_->ListFailureModes("", "interface_card");
  EXPECT_EQ(card->size(), 2u);
  EXPECT_EQ(catalogue_->GetFailureMode("failureModes/nope").status().code(), absl::StatusCode::kNotFound);
}

// Every field, bit for bit: what the diagnosis of a unit reads is what its
// unit type's catalogue says.
void ExpectSameSettings(const DiagnosisSettings& read, const DiagnosisSettings& given) {
  for (double DiagnosisSettings::*field :
       {&DiagnosisSettings::healthy_tolerance_sd, &DiagnosisSettings::healthy_log_ratio_fraction,
        &DiagnosisSettings::healthy_z_sd, &DiagnosisSettings::contamination, &DiagnosisSettings::broad_log_ratio,
        &DiagnosisSettings::broad_tolerance, &DiagnosisSettings::broad_z, &DiagnosisSettings::unknown_prior,
        &DiagnosisSettings::minimum_exposure_hours, &DiagnosisSettings::expert_pseudo_hours,
        &DiagnosisSettings::expert_signature_weight, &DiagnosisSettings::significance_level,
        &DiagnosisSettings::incidental_contamination, &DiagnosisSettings::trend_z_change,
        &DiagnosisSettings::trend_z_spread}) {
    EXPECT_EQ(std::bit_cast<std::uint64_t>(read.*field), std::bit_cast<std::uint64_t>(given.*field))
        << read.*field << " read back, " << given.*field << " given";
  }
  EXPECT_EQ(read.present_score_octaves, given.present_score_octaves);
}

TEST_F(KnowledgeBaseTest, TheDiagnosisSettingsReadBackAsTheCatalogueGivesThem) {
  const DiagnosisSettings& catalogue = testing::Ins2000().settings;
  ASSERT_GT(catalogue.healthy_tolerance_sd, 0.0) << "the catalogue's settings are set";
  auto inputs = diagnoses_->LoadInputs(StoreAnalysis("INS-0010", testing::NominalReport()));
  ASSERT_TRUE(inputs.ok()) << inputs.status();
  ExpectSameSettings(inputs->settings, catalogue);
  EXPECT_EQ(inputs->settings_note, "") << "its own settings";

  // Seeding again with other values replaces them.
  DiagnosisSettings changed = catalogue;
  changed.significance_level = 0.1 + 0.2;  // not 0.3: a value with no short decimal
  changed.present_score_octaves = 7;
  const UnitTypeDiagnosisSettings seeded{"unitTypes/INS-2000", changed};
  ASSERT_TRUE(catalogue_->Seed({}, {}, {&seeded, 1}).ok());
  auto again = diagnoses_->LoadInputs(inputs->analysis_name);
  ASSERT_TRUE(again.ok()) << again.status();
  ExpectSameSettings(again->settings, changed);
}

TEST_F(KnowledgeBaseTest, ARunOfANewSerialRegistersTheUnitWithItsModules) {
  StoreAnalysis("INS-0001", testing::NominalReport());
  auto unit = catalogue_->GetUnit("units/INS-0001");
  ASSERT_TRUE(unit.ok()) << unit.status();
  EXPECT_EQ(unit->unit_type, "unitTypes/INS-2000");
  auto modules = catalogue_->ListModules("units/INS-0001");
  ASSERT_TRUE(modules.ok());
  EXPECT_EQ(modules->size(), 10u);
}

// A unit type the knowledge base knows but has no built-in failure modes for
// is diagnosed with the default catalogue's settings, and the diagnosis says so.
TEST_F(KnowledgeBaseTest, AUnitTypeWithoutBuiltInFailureModesIsDiagnosedWithSettingsItNames) {
  UnitType other = testing::Ins2000().unit_type;
  other.name = "unitTypes/INS-2000-LAB";
  other.display_name = "INS-2000 (lab variant)";
  ASSERT_TRUE(catalogue_->Seed({&other, 1}, {}, {}).ok());
  const std::string lab_analysis = StoreAnalysis("LAB-0001", WornGyroX(), "INS-2000-LAB");
  auto inputs = diagnoses_->LoadInputs(lab_analysis);
  ASSERT_TRUE(inputs.ok()) << inputs.status();
  ExpectSameSettings(inputs->settings, testing::Ins2000().settings);
  auto diagnosis = Diagnose(lab_analysis);
  ASSERT_TRUE(diagnosis.ok()) << diagnosis.status();
  EXPECT_THAT(diagnosis->notes(),
              ::testing::Contains(::testing::AllOf(
                  ::testing::HasSubstr("'INS-2000-LAB' has no built-in failure-mode"),
                  ::testing::HasSubstr("INS-2000's settings"))));
  auto own = Diagnose(StoreAnalysis("INS-0009", WornGyroX()));
  ASSERT_TRUE(own.ok()) << own.status();
  EXPECT_THAT(
      own->notes(),
      ::testing::Not(::testing::Contains(::testing::HasSubstr("no built-in failure-mode"))));
}

TEST_F(KnowledgeBaseTest, ConfirmingADiagnosisWritesAFailureRecordAndRaisesLaterPosteriors) {
  const std::string first = StoreAnalysis("INS-0002", WornGyroX());
  auto diagnosis = Diagnose(first);
  ASSERT_TRUE(diagnosis.ok()) << diagnosis.status();
  EXPECT_EQ(diagnosis->candidates(0).module(), "gyro.x");
  const double before = P(*diagnosis, "failureModes/dtg-bearing-wear.x");

  DiagnosisResolution resolve;
  resolve.name = diagnosis->name();
  resolve.module = "gyro.x";
  resolve.failure_mode = "failureModes/dtg-bearing-wear.x";
  resolve.confirmed = true;
  resolve.repair_action = "gyro replaced";
  auto resolved = diagnoses_->Resolve(resolve);
  ASSERT_TRUE(resolved.ok()) << resolved.status();
  EXPECT_TRUE(resolved->confirmed);
  EXPECT_FALSE(resolved->failure_record.empty());
  EXPECT_EQ(diagnoses_->Resolve(resolve).status().code(), absl::StatusCode::kFailedPrecondition);

  FailureRecordQuery unit_records;
  unit_records.unit = "units/INS-0002";
  auto records = records_->List(unit_records);
  ASSERT_TRUE(records.ok());
  ASSERT_EQ(records->first.size(), 1u);
  EXPECT_TRUE(records->first[0].confirmed);
  EXPECT_EQ(records->first[0].module, "units/INS-0002/modules/gyro.x");
  EXPECT_EQ(records->first[0].analysis, first);
  auto mode = catalogue_->GetFailureMode("failureModes/dtg-bearing-wear.x");
  EXPECT_EQ(mode->confirmed_failures, 1);
  EXPECT_EQ(mode->signature[0].confirmed_cases, 1);
  EXPECT_NE(mode->signature[0].change, mode->signature[0].expert_change);

  // Another unit with the same evidence: the mode is now more probable.
  auto later = Diagnose(StoreAnalysis("INS-0003", WornGyroX()));
  ASSERT_TRUE(later.ok());
  EXPECT_GT(P(*later, "failureModes/dtg-bearing-wear.x"), before);

  // A rejection is a no-fault-found record and leaves the mode's count alone.
  auto other = Diagnose(StoreAnalysis("INS-0004", WornGyroX()));
  resolve.name = other->name();
  resolve.confirmed = false;
  auto rejected = diagnoses_->Resolve(resolve);
  ASSERT_TRUE(rejected.ok()) << rejected.status();
  EXPECT_FALSE(rejected->confirmed);
  EXPECT_EQ(catalogue_->GetFailureMode("failureModes/dtg-bearing-wear.x")->confirmed_failures, 1);

  FleetStore fleet(pool());
  auto stats = fleet.GetFleetStatistics({});
  ASSERT_TRUE(stats.ok()) << stats.status();
  EXPECT_EQ(stats->failure_count, 1);
  EXPECT_EQ(stats->no_fault_found_count, 1);
  auto pareto = fleet.GetFailurePareto({});
  ASSERT_TRUE(pareto.ok());
  ASSERT_FALSE(pareto->entries.empty());
  EXPECT_EQ(pareto->entries[0].failure_mode, "failureModes/dtg-bearing-wear.x");
  EXPECT_EQ(pareto->entries[0].failures, 1);
  auto ranked = fleet.RankUnits({});
  ASSERT_TRUE(ranked.ok()) << ranked.status();
  EXPECT_EQ(ranked->units.size(), 3u);
}

TEST_F(KnowledgeBaseTest, RefusesMalformedRecordsNamingTheField) {
  StoreAnalysis("INS-0005", testing::NominalReport());
  FailureRecord record;
  record.module = "units/INS-0005/modules/gyro.x";
  record.confirmed = true;
  EXPECT_THAT(records_->Create(record).status().message(),
              ::testing::HasSubstr("failure_record.failure_mode"));
  record.failure_mode = "failureModes/acc-bias-shift.x";
  EXPECT_THAT(records_->Create(record).status().message(), ::testing::HasSubstr("is a failure of acc.x"));
  record.module = "units/INS-0005/modules/wheel";
  EXPECT_EQ(records_->Create(record).status().code(), absl::StatusCode::kInvalidArgument);
  record.module = "units/INS-0005/modules/acc.x";
  auto ok = records_->Create(record);
  EXPECT_TRUE(ok.ok()) << ok.status();
}

// A correction changes the record that every count reads, and keeps the
// version it replaced with its reason: the FRACAS history is never lost.
TEST_F(KnowledgeBaseTest, ACorrectedRecordKeepsItsReplacedVersionAndCountsAsCorrected) {
  StoreAnalysis("INS-0006", testing::NominalReport());
  FailureRecord record;
  record.module = "units/INS-0006/modules/acc.x";
  record.confirmed = true;
  record.failure_mode = "failureModes/acc-bias-shift.x";
  record.operating_hours = 1200.0;
  auto created = records_->Create(record);
  ASSERT_TRUE(created.ok()) << created.status();
  EXPECT_EQ(created->revision, 1);
  EXPECT_EQ(created->detected_time, created->record_time) << "an unset detected time is the time of writing";
  auto confirmed_count = [&] {
    auto mode = catalogue_->GetFailureMode("failureModes/acc-bias-shift.x");
    EXPECT_TRUE(mode.ok()) << mode.status();
    return mode.ok() ? mode->confirmed_failures : -1;
  };
  EXPECT_EQ(confirmed_count(), 1);

  // The bench found nothing after all.
  FailureRecord facts;
  facts.no_fault_found = true;
  facts.operating_hours = 1250.0;
  facts.notes = "retest passed";
  EXPECT_EQ(records_->Correct(created->name, facts, "").status().code(),
            absl::StatusCode::kInvalidArgument) << "a correction without a reason";
  auto corrected = records_->Correct(created->name, facts, "retest on bench 2 found no fault");
  ASSERT_TRUE(corrected.ok()) << corrected.status();
  EXPECT_EQ(corrected->revision, 2);
  EXPECT_FALSE(corrected->confirmed);
  EXPECT_TRUE(corrected->no_fault_found);
  EXPECT_EQ(corrected->module, created->module);
  EXPECT_EQ(corrected->detected_time, created->detected_time) << "an unset detected time is kept";
  EXPECT_EQ(confirmed_count(), 0) << "counts read the corrected record";

  auto history = records_->ListRevisions(created->name);
  ASSERT_TRUE(history.ok()) << history.status();
  ASSERT_EQ(history->size(), 1u);
  const FailureRecordRevision& was = history->front();
  EXPECT_EQ(was.failure_record.revision, 1);
  EXPECT_TRUE(was.failure_record.confirmed);
  EXPECT_EQ(was.failure_record.failure_mode, "failureModes/acc-bias-shift.x");
  EXPECT_EQ(was.failure_record.operating_hours, 1200.0);
  EXPECT_EQ(was.reason, "retest on bench 2 found no fault");

  // A mode of another module is refused and changes nothing.
  facts.no_fault_found = false;
  facts.confirmed = true;
  facts.failure_mode = "failureModes/dtg-bearing-wear.x";
  EXPECT_EQ(records_->Correct(created->name, facts, "wrong").status().code(),
            absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(records_->ListRevisions(created->name)->size(), 1u);
  EXPECT_EQ(records_->Correct("failureRecords/00000000-0000-4000-8000-000000000000", facts, "x")
                .status().code(),
            absl::StatusCode::kNotFound);
}

// Records and diagnoses page newest first by (time, id): page by page they
// are the whole list in its order, and a token the server did not issue is refused.
TEST_F(KnowledgeBaseTest, ListsRecordsAndDiagnosesPageByPage) {
  const std::string unit = "units/INS-0007";
  std::vector<std::string> analyses;
  for (int i = 0; i < 3; ++i) analyses.push_back(StoreAnalysis("INS-0007", testing::NominalReport()));
  for (const auto& analysis : analyses) {
    ASSERT_TRUE(Diagnose(analysis).ok());
    FailureRecord record;
    record.module = unit + "/modules/acc.x";
    record.analysis = analysis;
    ASSERT_TRUE(records_->Create(record).ok());
  }
  // The names of every page of `list(query)`, `page_size` at a time.
  const auto names = [](auto list, auto query, int page_size) {
    std::vector<std::string> out;
    query.page.page_size = page_size;
    for (int pages = 0; pages < 10; ++pages) {
      auto page = list(query);
      EXPECT_TRUE(page.ok()) << page.status();
      if (!page.ok()) break;
      for (const auto& item : page->first) out.push_back(NameOf(item));
      if (page->second.empty()) break;
      query.page.page_token = page->second;
    }
    return out;
  };

  FailureRecordQuery records;
  records.unit = unit;
  const auto list_records = [&](const FailureRecordQuery& q) { return records_->List(q); };
  EXPECT_EQ(names(list_records, records, 50).size(), 3u);
  EXPECT_EQ(names(list_records, records, 1), names(list_records, records, 50));

  DiagnosisQuery diagnoses;
  diagnoses.unit = unit;
  const auto list_diagnoses = [&](const DiagnosisQuery& q) { return diagnoses_->List(q); };
  EXPECT_EQ(names(list_diagnoses, diagnoses, 50).size(), 3u);
  EXPECT_EQ(names(list_diagnoses, diagnoses, 1), names(list_diagnoses, diagnoses, 50));

  records.page.page_token = absl::WebSafeBase64Escape("2024-01-01 00:00:00+00|not-a-uuid");
  EXPECT_EQ(records_->List(records).status().code(), absl::StatusCode::kInvalidArgument);
  diagnoses.page.page_token = "not a token";
  EXPECT_EQ(diagnoses_->List(diagnoses).status().code(), absl::StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace insdiag::kb
