// A failure mode's signature learnt from its confirmed cases. Whatever
// changes which records confirm a mode (a new record, a correction, a
// resolved diagnosis) refines it in that change's transaction, so the next
// diagnosis reads signatures consistent with the records.
#pragma once

#include <absl/status/status.h>

#include <string>

#include "insdiag/kb/analysis.h"
#include "insdiag/kb/pg.h"

namespace insdiag::kb::internal {

// Re-derives the signature of `mode_id` from the expert values and every
// confirmed case with an analysis (kb/diagnosis.h, RefineSignature), its
// report's bytes read by `decode_report`. An unknown mode is left alone.
absl::Status RefineModeSignature(Connection& db, const std::string& mode_id, const ReportDecoder& decode_report);

}  // namespace insdiag::kb::internal
