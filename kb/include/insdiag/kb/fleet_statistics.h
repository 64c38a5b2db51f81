// The questions FleetStore answers and its answers (docs/FLEET.md), as plain
// values. Resources are named as the API names them: unitTypes/{t},
// failureModes/{m}, units/{serial}, analyses/{a}, diagnoses/{d}. A filter
// left empty applies to the whole fleet; a confidence of 0 is the default
// 0.90. Hours are operating hours of the unit or part.
#pragma once

#include <absl/time/time.h>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "insdiag/kb/page_query.h"
#include "insdiag/kb/reliability.h"

namespace insdiag::kb {

struct FleetStatisticsQuery {
  std::string unit_type;
  double confidence = 0.0;  // of the MTBF bounds, within [0, 1)
};

// Failures and exposure of the installed parts of one module role.
struct ModuleFailureRate {
  std::string module_role;
  std::int64_t failures = 0;     // confirmed failure records
  double operating_hours = 0.0;  // total exposure, censored parts included
  double failures_per_million_hours = 0.0;
  double mtbf_hours = 0.0;        // 0 without failures
  double mtbf_lower_hours = 0.0;  // time-terminated χ² bounds (kb/reliability.h)
  double mtbf_upper_hours = 0.0;  // 0: unbounded (no failures)
  std::int64_t no_fault_found = 0;
  std::int64_t modules = 0;  // installed parts of the role, present and past
};

struct FleetStatistics {
  std::string unit_type;
  std::int64_t unit_count = 0;
  std::int64_t run_count = 0;
  std::int64_t analysis_count = 0;
  std::vector<ModuleFailureRate> failure_rates;  // by module role
  double confidence = 0.0;                       // the one used
  std::int64_t failure_count = 0;                // confirmed
  std::int64_t no_fault_found_count = 0;
  // When the unit, run and analysis counts were last refreshed; none before
  // the views hold a row.
  std::optional<absl::Time> counts_time;
};

struct FailureCountQuery {
  std::string unit_type;
  std::string period;                    // "month" (when empty), "quarter" or "year"
  std::optional<absl::Time> start_time;  // detected at or after
  std::optional<absl::Time> end_time;    // detected before
  std::string failure_mode;
  std::string batch;
};

// Confirmed failures of one mode, unit type and batch in one period.
struct FailureCount {
  std::string failure_mode;
  std::string module_role;
  std::string unit_type;  // empty for units without a type
  std::string batch;
  absl::Time period_start;
  std::int64_t failures = 0;
};

struct FailureCounts {
  std::vector<FailureCount> counts;  // by period, mode, unit type, batch
  std::int64_t total = 0;
};

struct FailureParetoQuery {
  std::string unit_type;
};

struct ParetoEntry {
  std::string failure_mode;
  std::string module_role;
  std::string display_name;
  std::int64_t failures = 0;
  double share = 0.0;  // of all confirmed failures
  double cumulative_share = 0.0;
};

struct FailurePareto {
  std::string unit_type;
  std::int64_t total_failures = 0;
  std::vector<ParetoEntry> entries;  // most failures first
};

struct WeibullFitQuery {
  std::string unit_type;
  std::string module_role;   // required, e.g. gyro.x
  std::string failure_mode;  // empty: any failure of the role
  double confidence = 0.0;   // of the bounds, within [0, 1)
};

// The role's Weibull life (kb/reliability.h) with what it was asked for.
struct WeibullFit {
  std::string unit_type;
  std::string module_role;
  std::string failure_mode;
  double confidence = 0.0;  // the one used
  WeibullEstimate estimate;
};

// The raw values of one identified parameter, oldest analysis first.
struct ParameterPointQuery {
  std::string unit_type;
  std::string parameter;  // e.g. gyro_bias_gm.x.sigma
  std::string unit;       // only this unit, when set
  PageQuery page;         // page size: 0 or less for 50, at most 1000
};

struct ParameterPoint {
  std::string unit;
  std::string analysis;
  double operating_hours = 0.0;  // of the unit at the analysis
  double value = 0.0;
  double std_error = 0.0;
  absl::Time time;  // of the analysis
};

struct ParameterPointPage {
  std::vector<ParameterPoint> points;
  std::string next_page_token;  // empty on the last page
};

struct ParameterTrendQuery {
  std::string unit_type;  // required
  std::string parameter;  // required
  std::string batch;      // only this batch, when set
};

// One batch's values of the parameter in one month.
struct TrendBucket {
  std::string batch;
  absl::Time month;
  std::int64_t count = 0;
  double median = 0.0;
  double p25 = 0.0;
  double p75 = 0.0;
  double mean = 0.0;
};

struct ParameterTrend {
  std::string unit_type;
  std::string parameter;
  // The unit type's nominal value and the values' unit; 0 and empty when
  // the unit type has none.
  std::string unit;
  double nominal = 0.0;
  double tolerance = 0.0;
  std::vector<TrendBucket> buckets;  // by batch, then month
  // Count-weighted least-squares slope of the monthly medians, in the
  // parameter's unit per year and relative to nominal; 0 when the buckets
  // do not determine it (or, relative, without a nominal).
  double slope_per_year = 0.0;
  double relative_slope_per_year = 0.0;
  std::optional<absl::Time> refreshed_time;  // of the buckets; none without
};

struct UnitRankingQuery {
  std::string unit_type;
  PageQuery page;  // page size: 0 or less for 50, at most 1000
};

// A unit by the fault probability of its latest diagnosis.
struct RankedUnit {
  std::string unit;
  std::string unit_type;  // empty for a unit without a type
  std::string batch;
  double fault_probability = 0.0;  // 1 − P(healthy)
  std::string top_module;          // the most probable faulty module
  std::string top_failure_mode;
  double top_probability = 0.0;
  std::string diagnosis;
  double operating_hours = 0.0;
};

struct UnitRankingPage {
  std::vector<RankedUnit> units;  // most probable first
  std::string next_page_token;    // empty on the last page
};

}  // namespace insdiag::kb
