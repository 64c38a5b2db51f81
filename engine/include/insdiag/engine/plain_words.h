// The verdict in plain words: the few lines a quality engineer reads first —
// what is wrong, where, how sure, what to do — before the tables and the
// engine's notes. Each finding says what the raw samples show around it (a
// step: the sensor's minute means either side of its onset), so that a
// person can check it without the model.
#pragma once

#include <string>
#include <vector>

#include "insdiag/engine/bench_run.h"
#include "insdiag/engine/report.h"

namespace insdiag::engine {

// At most this many lines: the verdict, up to three findings, what to do.
inline constexpr int kPlainWordsMaxLines = 5;

// `run` is the run the report was computed on (its raw samples are quoted).
std::vector<std::string> PlainWordsVerdict(const AnalysisReport& report, const BenchRun& run,
                                           double family_wise_alpha);

}  // namespace insdiag::engine
