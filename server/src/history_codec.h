// A unit's history between the knowledge base's domain types
// (kb/unit_history_store.h, kb/unit_history.h) and its API form (insdiag.v1,
// history.proto). The mapping sits here, at the API edge, so that the
// knowledge base never sees a protobuf message.
#pragma once

#include "insdiag/kb/unit_history.h"
#include "insdiag/kb/unit_history_store.h"
#include "insdiag/v1/history.pb.h"

namespace insdiag::server {

kb::UnitHistoryQuery UnitHistoryQueryOf(const v1::GetUnitHistoryRequest& request);

// An unfitted trend is all zeros, as FitTrend leaves it.
v1::UnitTrendFit ToProto(const kb::TrendFit& fit);
// turn_on_to_turn_on_sd and trend stay unset when absent.
v1::UnitParameterStatistics ToProto(const kb::ParameterStatistics& statistics);
v1::UnitParameterHistory ToProto(const kb::ParameterHistory& history);
// An analysis without a verdict has VERDICT_UNSPECIFIED.
v1::UnitHistory ToProto(const kb::UnitHistory& history);

}  // namespace insdiag::server
