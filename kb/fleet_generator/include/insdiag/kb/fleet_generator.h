// The fleet generator (docs/FLEET.md): years of history of a unit type's
// fleet — units in production batches, their modules with installation
// history, periodic bench tests with their analyses, failures, removals,
// diagnoses — written straight into the knowledge base with COPY, for demos,
// the fleet statistics and their benchmark. Deterministic: the same options
// (seed and end time included) give the same fleet. Its own library,
// insdiag::fleet_generator (kb/fleet_generator/), which uses insdiag::kb; the
// production library does not contain it.
//
// Every physical value comes from the data files: the unit type's nominal
// values and tolerances (data/unit-types), its failure modes' signatures and
// Weibull lives (data/failure-modes), the diagnosis settings' healthy
// scatter, and the fleet profile (data/fleets: usage, test interval,
// ageing, no-fault-found rate, precursor window).
//
// Model (t calendar time, h a unit's operating hours, h = r·(t − t_commission)):
//   units        commissioned evenly over `history_years`, batch = commission
//                period; usage r = r₀·exp(s_r·N); withdrawn at Exp(retirement) years
//   parts        one per module role at commissioning; each part draws a life
//                T_m ~ Weibull(β_m, η_m) [operating hours since installation] for
//                every mode m of its role; it fails at min_m T_m by that mode
//                (competing risks) when that is before the present (or the
//                unit's withdrawal), is removed and replaced by a new part;
//                otherwise it is right-censored at the present (or removed,
//                censored, at withdrawal)
//   tests        an acceptance test at commissioning, then every
//                test_interval·(1 ± jitter·U) days; an unscheduled test at
//                every failure (the analysis that found it) and every
//                no-fault-found removal (a Poisson process in h)
//   identified   ln(v/v₀) = b_batch + u_unit + a_batch·age_years + drift + e_test,
//                with b, u, e normal and Var b + Var u + Var e = s_h², the
//                healthy scatter of the diagnosis (healthy_log_ratio_fraction ·
//                ln(1 + T/v₀)), split by the profile's variance shares; a_batch
//                ~ N(ageing mean, batch sd) per year of service
//   effects      x = N(0, healthy_tolerance_sd) + drift (tolerance units), or
//                N(0, healthy_z_sd) + drift (standard scores) for effects
//                without a tolerance
//   drift        a failing part's signature terms move during the precursor
//                window before its failure: (1 − Δt/window)^p · c, with c ~
//                N(change, spread) per failure and the sign of the direction
//                (EITHER: ±1), shared by a `common` family, each member
//                moving with probability `fraction` otherwise
//   diagnoses    kb::Diagnose of the latest analysis of every unit and of every
//                unscheduled test; those of failures and no-fault-found
//                removals are resolved (confirmed / rejected) by their records
#pragma once

#include <absl/functional/function_ref.h>
#include <absl/status/status.h>
#include <absl/status/statusor.h>

#include <cstdint>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include "insdiag/kb/connection_pool.h"
#include "insdiag/v1/knowledge.pb.h"

namespace insdiag::kb {

// The fleet profiles insdiag ships with (data/fleets/*.json, built in).
std::vector<v1::FleetProfile> BuiltinFleetProfiles();
// By unit type display or resource name; NOT_FOUND when none.
absl::StatusOr<v1::FleetProfile> BuiltinFleetProfile(const std::string& unit_type);

struct FleetGeneratorOptions {
  std::string unit_type = "INS-2000";  // a built-in unit type with failure modes and a fleet profile
  int units = 0;                       // 0: the profile's
  // Periodic analyses in the whole fleet: sets the test interval so that the
  // fleet's service time holds this many. 0: the profile's interval.
  std::int64_t analyses = 0;
  std::uint64_t seed = 1;
  // The present of the history, µs since the epoch (UTC). 0: now, rounded
  // down to the day.
  std::int64_t end_time_micros = 0;
  double history_years = 0;             // 0: the profile's
  double operating_hours_per_year = 0;  // 0: the profile's
  // Serials are {prefix}-{n}; empty: "G{seed}". Serials must be new.
  std::string serial_prefix;
  // The bench-run format the run rows name (metadata only: no samples).
  std::string run_format = "insdiag-bench-run/1";
  // Replaces the built-in profile (tests).
  std::optional<v1::FleetProfile> profile;
  // Re-derive the failure modes' signatures from the confirmed cases and
  // refresh the fleet views after writing.
  bool refine_signatures = true;
  bool refresh_views = true;

  absl::Status Validate() const;
};

// What the generator knows to be true of the fleet it wrote, for tests and
// the tool's summary. Months are UTC month starts, µs since the epoch.
struct FleetTruth {
  // Confirmed failures by failure mode id (no prefix), batch and detection month.
  std::map<std::tuple<std::string, std::string, std::int64_t>, std::int64_t> failures;
  // Analyses by batch and month of their creation.
  std::map<std::pair<std::string, std::int64_t>, std::int64_t> analyses;
  // The batches' ageing rates: d ln(v/v₀)/dt per year, by (batch, parameter).
  std::map<std::pair<std::string, std::string>, double> ageing_per_year;
  // Parts of a module role's lives: installed parts, and those failed (any mode).
  std::map<std::string, std::int64_t> parts_by_role;
  // Units in service whose latest analysis shows a part's signature at
  // least half-way to its failure, which lies ahead (the failing parts a
  // diagnosis can see now; a failure whose signature moves nothing the
  // analyses measure is not among them).
  std::set<std::string> units_about_to_fail;
  std::map<std::string, std::string> batch_of_unit;  // serial → batch
  std::map<std::string, std::int64_t> analyses_of_unit;  // serial → analyses
  double fleet_operating_hours = 0;  // at the present (or withdrawal)
  double test_interval_days = 0;     // as used
};

struct GeneratedFleet {
  std::int64_t units = 0;
  std::int64_t retired_units = 0;
  std::int64_t modules = 0;  // installed parts, present and past
  std::int64_t runs = 0;
  std::int64_t analyses = 0;  // periodic and unscheduled
  std::int64_t identified_parameters = 0;
  std::int64_t effect_candidates = 0;
  std::int64_t confirmed_failures = 0;
  std::int64_t no_fault_found = 0;
  std::int64_t censored_records = 0;
  std::int64_t diagnoses = 0;
  std::vector<std::string> notes;  // e.g. signature terms the unit type cannot express
  FleetTruth truth;
};

// Seeds the built-in unit types and failure modes (idempotent), then writes
// the fleet in one transaction; `progress` hears each stage. INVALID_ARGUMENT
// for bad options, NOT_FOUND for a unit type without data, ALREADY_EXISTS
// when a serial is taken (choose another prefix).
absl::StatusOr<GeneratedFleet> GenerateFleet(ConnectionPool& pool, const FleetGeneratorOptions& options,
                                             absl::FunctionRef<void(const std::string&)> progress);

}  // namespace insdiag::kb
