// An analysis as the knowledge base keeps it (migrations/0002_knowledge.sql,
// table `analyses` and the report's rows beside it); its API form is
// insdiag.v1.Analysis (proto/insdiag/v1/analyses.proto), mapped at the
// server's edge (server/src/analysis_codec.h).
//
// The spec and the report are documents kb keeps and hands back without
// reading them: the bytes the edge encoded. What kb does read of a report,
// the rows the fleet statistics and the diagnosis query, arrives beside the
// bytes as ReportRows.
#pragma once

#include <absl/status/statusor.h>
#include <absl/time/time.h>

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "insdiag/engine/monitor/monitoring.h"
#include "insdiag/kb/diagnosis.h"

namespace insdiag::kb {

enum class AnalysisState { kUnspecified, kQueued, kRunning, kSucceeded, kFailed, kCancelled };

// "QUEUED", "RUNNING", … as the table and the API spell them;
// "STATE_UNSPECIFIED" for kUnspecified.
const char* AnalysisStateName(AnalysisState state);

struct ChannelMetricRow {
  std::string channel;  // lat, lon, height, vel_n, vel_e, vel_d, att_n, att_e, att_d
  double rms = 0.0;
  double fit_percent = 0.0;
  double nis_mean = 0.0;
  double whiteness_p_value = 0.0;
  std::int64_t sample_count = 0;
};

struct IdentifiedParameterRow {
  std::string name;  // "gyro_bias_gm.x.sigma"
  double value = 0.0;
  double std_error = 0.0;
  std::string method;  // the API's name: "ACF", "ALLAN", "FILTER", "ML", "STATIC", "METHOD_UNSPECIFIED"
  std::optional<double> a_priori;
};

struct EffectCandidateRow {
  std::string name;
  std::string family;
  std::string source;
  double statistic = 0.0;
  int degrees_of_freedom = 0;
  double p_value = 0.0;
  double p_value_holm = 0.0;
  double estimate = 0.0;
  double std_error = 0.0;
  std::string unit;
  bool identifiable = false;
  double predicted_delta_aic = 0.0;
};

struct FaultIntervalRow {
  std::string channel;
  double start_s = 0.0;
  double end_s = 0.0;
  std::optional<engine::FaultKind> kind;  // none: the report names none
  double peak_statistic = 0.0;
};

// The queryable parts of a report: written beside its bytes at Complete,
// and all there is of a report stored without them (the fleet generator's).
struct ReportRows {
  std::optional<engine::Verdict> verdict;  // none: the report states none
  double nis_mean = 0.0;
  double log_likelihood = 0.0;
  double aic = 0.0;
  double bic = 0.0;
  std::vector<IdentifiedParameterRow> identified;  // read back by name
  std::vector<EffectCandidateRow> effect_candidates;  // per term; read back by Holm p-value, then name
  std::vector<EffectCandidateRow> family_candidates;  // per family; likewise
  std::vector<ChannelMetricRow> channels;  // read back in the engine's channel order
  std::vector<FaultIntervalRow> fault_intervals;  // in the report's order
};

// A SUCCEEDED analysis's report: its bytes when stored, else its rows.
struct StoredReport {
  std::optional<std::string> encoded;
  ReportRows rows;  // read only when `encoded` is unset
};

struct AnalysisError {
  int code = 0;  // absl::StatusCode's number
  std::string message;
};

struct Analysis {
  std::string name;  // analyses/{analysis}
  std::string run;   // runs/{run}
  std::string unit;  // units/{serial}
  std::string encoded_spec;  // the spec as the edge encoded it at Create
  AnalysisState state = AnalysisState::kUnspecified;
  double progress_fraction = 0.0;
  std::string progress_stage;
  std::optional<AnalysisError> error;  // when FAILED
  int attempts = 0;
  absl::Time create_time;
  absl::Time update_time;
  std::optional<StoredReport> report;  // when SUCCEEDED and the report was asked for
};

// A stretch of the stored residual series, one observed epoch of one channel
// per point.
struct ResidualPoint {
  std::string channel;
  double t_s = 0.0;
  double measured = 0.0;
  double predicted = 0.0;
  double residual = 0.0;
  double sigma3 = 0.0;  // 3·√(HPHᵀ+R)
};

// What the diagnosis reads of a report kept as bytes; the edge decodes them.
using ReportDecoder = std::function<absl::StatusOr<ReportFindings>(std::string_view encoded_report)>;

// What the diagnosis reads of a report stored without its bytes: verdict,
// identified parameters and per-term candidates, as the report rebuilt from
// the rows gives them; no model effects (the analyses stored so, the fleet
// generator's, have no spec either).
ReportFindings FindingsOfRows(const ReportRows& rows);

// The findings of `report`: decoded when it has bytes, else of its rows.
absl::StatusOr<ReportFindings> ReportFindingsOf(const StoredReport& report, const ReportDecoder& decode);

}  // namespace insdiag::kb
