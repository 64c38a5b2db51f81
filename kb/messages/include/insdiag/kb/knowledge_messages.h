// The knowledge base's terms (kb/knowledge.h, kb/diagnosis.h) to and from
// the API's messages (proto/insdiag/v1/knowledge.proto, analyses.proto):
// where the stores read the expert catalogues, keep diagnoses in the API's
// form and answer with messages.
#pragma once

#include <absl/status/statusor.h>
#include <absl/time/time.h>

#include <string>
#include <string_view>

#include "insdiag/kb/diagnosis.h"
#include "insdiag/kb/diagnosis_store.h"
#include "insdiag/kb/knowledge.h"
#include "insdiag/v1/analyses.pb.h"
#include "insdiag/v1/knowledge.pb.h"

namespace insdiag::kb {

UnitType UnitTypeOf(const v1::UnitType& message);
v1::UnitType ToProto(const UnitType& unit_type);

// A scale outside log_ratio, tolerance and z (the catalogue and the
// database refuse them) reads as tolerance; a missing direction as either.
Signature SignatureOf(const v1::Signature& message);
v1::Signature ToProto(const Signature& signature);
FailureMode FailureModeOf(const v1::FailureMode& message);
v1::FailureMode ToProto(const FailureMode& mode);

DiagnosisSettings SettingsOf(const v1::DiagnosisSettings& message);

// Name, create time and resolution are the store's.
v1::Diagnosis ToProto(const Diagnosis& diagnosis);
// The diagnosis in the API's encoding with the name and create time the
// store gives it (a DiagnosisEncoder), and a stored diagnosis as the API
// shows it, with its resolution; INTERNAL for bytes that are no diagnosis.
std::string EncodeDiagnosis(const Diagnosis& diagnosis, const std::string& name, absl::Time create_time);
absl::StatusOr<v1::Diagnosis> DecodeDiagnosis(const StoredDiagnosis& stored);

ReportFindings FindingsOf(const v1::AnalysisReport& report);
// What the diagnosis reads of a stored report's bytes (a ReportDecoder,
// kb/analysis.h): the report decoded as far as it parses — a read never
// refused a stored report — and its findings.
absl::StatusOr<ReportFindings> DecodeReportFindings(std::string_view encoded_report);

}  // namespace insdiag::kb
