#include "knowledge_codec.h"

#include <gtest/gtest.h>

namespace insdiag::server {
namespace {

TEST(KnowledgeCodec, AUnitKeepsEveryFieldAndAnUncommissionedOneHasNoCommissionTime) {
  kb::Unit unit;
  unit.name = "units/INS-0001";
  unit.unit_type = "unitTypes/INS-2000";
  unit.operating_hours = 1234.5;
  unit.create_time = absl::FromUnixMicros(1'700'000'000'123'456);
  unit.batch = "2023Q2";
  unit.retired = true;
  v1::Unit message = ToProto(unit);
  EXPECT_EQ(message.name(), "units/INS-0001");
  EXPECT_EQ(message.unit_type(), "unitTypes/INS-2000");
  EXPECT_EQ(message.operating_hours(), 1234.5);
  EXPECT_EQ(message.create_time().seconds(), 1'700'000'000);
  EXPECT_EQ(message.create_time().nanos(), 123'456'000);
  EXPECT_EQ(message.batch(), "2023Q2");
  EXPECT_FALSE(message.has_commission_time());
  EXPECT_TRUE(message.retired());

  unit.commission_time = absl::UnixEpoch();
  message = ToProto(unit);
  EXPECT_TRUE(message.has_commission_time()) << "the epoch is a time, not \"unset\"";
  EXPECT_EQ(message.commission_time().seconds(), 0);
}

TEST(KnowledgeCodec, AModuleKeepsEveryFieldAndAnInstalledOneHasNoRemovalTime) {
  kb::Module module;
  module.name = "units/INS-0001/modules/gyro.x";
  module.role = "gyro.x";
  module.part_serial = "DTG-77";
  module.installed_time = absl::FromUnixSeconds(1'600'000'000);
  module.installed_hours = 10.0;
  module.current = true;
  v1::Module message = ToProto(module);
  EXPECT_EQ(message.name(), module.name);
  EXPECT_EQ(message.role(), "gyro.x");
  EXPECT_EQ(message.part_serial(), "DTG-77");
  EXPECT_EQ(message.installed_time().seconds(), 1'600'000'000);
  EXPECT_EQ(message.installed_hours(), 10.0);
  EXPECT_FALSE(message.has_removed_time());
  EXPECT_TRUE(message.current());

  module.removed_time = absl::FromUnixSeconds(1'650'000'000);
  module.removed_hours = 2500.0;
  module.removal_reason = "bearing wear";
  module.current = false;
  message = ToProto(module);
  EXPECT_EQ(message.removed_time().seconds(), 1'650'000'000);
  EXPECT_EQ(message.removed_hours(), 2500.0);
  EXPECT_EQ(message.removal_reason(), "bearing wear");
  EXPECT_FALSE(message.current());
}

kb::FailureRecord EveryFieldSet() {
  kb::FailureRecord record;
  record.name = "failureRecords/0b0e8a4e-3a4b-4f43-9a54-6f0e2a1c9d10";
  record.module = "units/INS-0001/modules/acc.x";
  record.failure_mode = "failureModes/acc-bias-shift.x";
  record.analysis = "analyses/4d7f1e0c-4c1a-4b59-8a62-1f7a0e3d2b11";
  record.diagnosis = "diagnoses/9a1c2e33-0f4d-4e6b-b1a7-3c5d9e2f8a40";
  record.operating_hours = 1200.25;
  record.confirmed = true;
  record.no_fault_found = true;  // not a valid record, but the codec carries what it is given
  record.censored = true;
  record.repaired = true;
  record.repair_action = "module replaced";
  record.notes = "found on bench 2";
  record.detected_time = absl::FromUnixNanos(1'700'000'000'987'654'321);
  record.record_time = absl::FromUnixMicros(-1);
  record.revision = 3;
  return record;
}

TEST(KnowledgeCodec, AFailureRecordKeepsEveryFieldBothWays) {
  const kb::FailureRecord record = EveryFieldSet();
  const v1::FailureRecord message = ToProto(record);
  EXPECT_EQ(message.name(), record.name);
  EXPECT_EQ(message.module(), record.module);
  EXPECT_EQ(message.failure_mode(), record.failure_mode);
  EXPECT_EQ(message.analysis(), record.analysis);
  EXPECT_EQ(message.diagnosis(), record.diagnosis);
  EXPECT_EQ(message.operating_hours(), 1200.25);
  EXPECT_TRUE(message.confirmed());
  EXPECT_TRUE(message.no_fault_found());
  EXPECT_TRUE(message.censored());
  EXPECT_TRUE(message.repaired());
  EXPECT_EQ(message.repair_action(), "module replaced");
  EXPECT_EQ(message.notes(), "found on bench 2");
  EXPECT_EQ(message.detected_time().seconds(), 1'700'000'000);
  EXPECT_EQ(message.detected_time().nanos(), 987'654'321);
  EXPECT_EQ(message.record_time().seconds(), -1);  // nanos stay in [0, 1e9)
  EXPECT_EQ(message.record_time().nanos(), 999'999'000);
  EXPECT_EQ(message.revision(), 3);

  const kb::FailureRecord back = FromProto(message);
  EXPECT_EQ(back.name, record.name);
  EXPECT_EQ(back.module, record.module);
  EXPECT_EQ(back.failure_mode, record.failure_mode);
  EXPECT_EQ(back.analysis, record.analysis);
  EXPECT_EQ(back.diagnosis, record.diagnosis);
  EXPECT_EQ(back.operating_hours, record.operating_hours);
  EXPECT_EQ(back.confirmed, record.confirmed);
  EXPECT_EQ(back.no_fault_found, record.no_fault_found);
  EXPECT_EQ(back.censored, record.censored);
  EXPECT_EQ(back.repaired, record.repaired);
  EXPECT_EQ(back.repair_action, record.repair_action);
  EXPECT_EQ(back.notes, record.notes);
  EXPECT_EQ(back.detected_time, record.detected_time);
  EXPECT_EQ(back.record_time, record.record_time);
  EXPECT_EQ(back.revision, record.revision);
}

// A correction without a detected time keeps the record's: unset must not
// turn into the epoch on the way in, nor on the way out.
TEST(KnowledgeCodec, AnUnsetDetectedTimeStaysUnset) {
  v1::FailureRecord facts;
  facts.set_no_fault_found(true);
  const kb::FailureRecord domain = FromProto(facts);
  EXPECT_FALSE(domain.detected_time.has_value());
  EXPECT_FALSE(ToProto(domain).has_detected_time());

  facts.mutable_detected_time()->set_seconds(0);
  EXPECT_EQ(FromProto(facts).detected_time, absl::UnixEpoch()) << "the epoch, set, is a time";
}

TEST(KnowledgeCodec, ARevisionKeepsTheRecordAsItWasAndTheCorrection) {
  kb::FailureRecordRevision revision;
  revision.failure_record = EveryFieldSet();
  revision.superseded_time = absl::FromUnixSeconds(1'710'000'000);
  revision.reason = "retest on bench 2 found no fault";
  const v1::FailureRecordRevision message = ToProto(revision);
  EXPECT_EQ(message.failure_record().name(), revision.failure_record.name);
  EXPECT_EQ(message.failure_record().revision(), 3);
  EXPECT_EQ(message.superseded_time().seconds(), 1'710'000'000);
  EXPECT_EQ(message.reason(), revision.reason);
}

}  // namespace
}  // namespace insdiag::server
