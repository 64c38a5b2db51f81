// Analyses, their specs, reports and residual series between the knowledge
// base's values (kb/analysis.h) and their API form (insdiag.v1,
// analyses.proto). kb keeps the spec and the report as the bytes encoded
// here and reads only the report's rows, which are extracted here too; the
// mapping sits at the API edge so that the knowledge base never sees a
// protobuf message.
#pragma once

#include <absl/status/statusor.h>

#include <span>
#include <string>
#include <string_view>

#include "insdiag/kb/analysis.h"
#include "insdiag/v1/analyses.pb.h"

namespace insdiag::server {

std::string EncodedSpec(const v1::AnalysisSpec& spec);
// Bytes that do not parse give the spec as far as they parse (as they
// always have been read).
v1::AnalysisSpec SpecOf(std::string_view encoded_spec);

std::string EncodedReport(const v1::AnalysisReport& report);
// What the knowledge base queries of `report`: verdict (none for
// VERDICT_UNSPECIFIED), headline figures, identified parameters, effect
// candidates, channel metrics and fault intervals.
kb::ReportRows ReportRowsOf(const v1::AnalysisReport& report);

// A report rebuilt from an analysis's rows (one stored without its bytes):
// the rows' fields, the model read from `encoded_spec`, each channel's unit
// from its name, and a note saying it was rebuilt.
v1::AnalysisReport RebuiltReport(const kb::ReportRows& rows, std::string_view encoded_spec);
// The stored bytes decoded, else the report rebuilt from the rows.
v1::AnalysisReport ReportOf(const kb::StoredReport& report, std::string_view encoded_spec);

// The spec's model, baseline, discover and base analysis come from its
// bytes; the error only when FAILED; the report only when kb holds one.
v1::Analysis ToProto(const kb::Analysis& analysis);
v1::Analysis::State ToProto(kb::AnalysisState state);
v1::ResidualSeriesChunk ToProto(std::span<const kb::ResidualPoint> points);

}  // namespace insdiag::server
