// The fleet generator's entry points and the built-in fleet profiles: the
// model from the data files, the plan, the COPY in one transaction, then the
// knowledge base's derived state (statistics, signatures, views).
#include "insdiag/kb/fleet_generator.h"

#include <absl/strings/str_cat.h>
#include <absl/strings/str_format.h>

#include <chrono>

#include "fleet_profile_data.h"
#include "generator.h"
#include "insdiag/api/json.h"
#include "insdiag/api/resource_names.h"
#include "insdiag/engine/status_macros.h"
#include "insdiag/kb/catalogue_data.h"
#include "insdiag/kb/catalogue_store.h"
#include "insdiag/kb/diagnosis.h"
#include "insdiag/kb/diagnosis_store.h"
#include "insdiag/kb/fleet_store.h"
#include "insdiag/kb/knowledge_messages.h"

namespace insdiag::kb {
namespace {

using generator::kMicrosPerDay;

// The test interval: the profile's, or the one that gives the fleet's
// service time `options.analyses` periodic analyses.
absl::StatusOr<std::int64_t> TestInterval(const FleetGeneratorOptions& options, const generator::Model& m,
                                          const generator::Plan& plan, int units) {
  std::int64_t interval_us = static_cast<std::int64_t>(m.profile.test_interval_days() * static_cast<double>(kMicrosPerDay));
  if (options.analyses > 0) {
    // Each unit is tested at commissioning and then every interval: the
    // periodic analyses are ≈ units + service time / interval.
    if (options.analyses <= units) {
      return absl::InvalidArgumentError(
          absl::StrCat("analyses: ", options.analyses, " is not more than the ", units,
                       " acceptance tests at commissioning"));
    }
    double service_us = 0;
    for (const auto& u : plan.units) service_us += static_cast<double>(u.end_us - u.commission_us);
    interval_us = static_cast<std::int64_t>(service_us / static_cast<double>(options.analyses - units));
    if (interval_us <= 0) return absl::InvalidArgumentError("analyses: too many for the fleet's service time");
  }
  return interval_us;
}

// After the load: fresh planner statistics, and (as the options ask) the
// failure modes' signatures refined from the generated cases and the fleet
// views refreshed.
absl::Status UpdateDerivedState(ConnectionPool& pool, Connection& db, const FleetGeneratorOptions& options,
                                const std::string& unit_type, absl::FunctionRef<void(const std::string&)> progress) {
  const auto timed = [&](const std::string& what, absl::FunctionRef<absl::Status()> body) {
    const auto t0 = std::chrono::steady_clock::now();
    absl::Status s = body();
    if (s.ok()) {
      progress(absl::StrCat(what, " in ",
                            absl::StrFormat("%.1f", std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count()),
                            " s"));
    }
    return s;
  };
  if (auto s = timed("analysed the tables", [&] {
        return db.ExecScript(
            "ANALYZE units, modules, runs, analyses, identified_parameters, effect_candidates, failure_records, "
            "diagnoses, diagnosis_candidates");
      });
      !s.ok()) {
    return s;
  }
  if (options.refine_signatures) {
    if (auto s = timed("refined the failure modes' signatures",
                       [&] { return DiagnosisStore(pool, DecodeReportFindings).RefineSignatures(unit_type); });
        !s.ok()) {
      return s;
    }
  }
  if (options.refresh_views) {
    if (auto s = timed("refreshed the fleet views", [&] { return FleetStore(pool).RefreshViews(/*concurrently=*/false).status(); });
        !s.ok()) {
      return s;
    }
  }
  return absl::OkStatus();
}

}  // namespace

std::vector<v1::FleetProfile> BuiltinFleetProfiles() {
  std::vector<v1::FleetProfile> out;
  for (const std::string_view json : kFleetProfileJson) {
    v1::FleetProfile profile;
    // The files are part of the build and parsed by a test.
    if (api::FromJson(json, &profile).ok()) out.push_back(std::move(profile));
  }
  return out;
}

absl::StatusOr<v1::FleetProfile> BuiltinFleetProfile(const std::string& unit_type) {
  const std::string name = api::IdOrSelf(unit_type, api::kUnitTypes);
  for (auto& profile : BuiltinFleetProfiles()) {
    if (profile.unit_type() == name) return profile;
  }
  return absl::NotFoundError(absl::StrCat("no fleet profile for unit type '", unit_type, "' (data/fleets/)"));
}

absl::Status FleetGeneratorOptions::Validate() const {
  if (units < 0) return absl::InvalidArgumentError("units must not be negative (0: the profile's)");
  if (analyses < 0) return absl::InvalidArgumentError("analyses must not be negative (0: the profile's interval)");
  if (history_years < 0 || operating_hours_per_year < 0) {
    return absl::InvalidArgumentError("history years and operating hours per year must not be negative");
  }
  if (end_time_micros < 0) return absl::InvalidArgumentError("the end time must be after 1970");
  if (serial_prefix.find_first_of("/\t\n\\") != std::string::npos) {
    return absl::InvalidArgumentError("serial prefix: no '/', backslash, tab or newline");
  }
  return absl::OkStatus();
}

absl::StatusOr<GeneratedFleet> GenerateFleet(ConnectionPool& pool, const FleetGeneratorOptions& options,
                                             absl::FunctionRef<void(const std::string&)> progress) {
  INSDIAG_RETURN_IF_ERROR(options.Validate());
  CatalogueStore catalogue(pool);
  INSDIAG_RETURN_IF_ERROR(SeedBuiltinCatalogues(catalogue));
  INSDIAG_ASSIGN_OR_RETURN(auto db, pool.Acquire());
  INSDIAG_ASSIGN_OR_RETURN(auto roles, db->Exec("SELECT role FROM module_roles ORDER BY role"));
  std::vector<std::string> role_names;
  for (int r = 0; r < roles.rows(); ++r) role_names.push_back(roles.String(r, 0));
  INSDIAG_ASSIGN_OR_RETURN(auto model, generator::BuildModel(options, role_names));
  const generator::Model& m = model;

  const auto start = std::chrono::steady_clock::now();
  generator::Plan plan;
  const int units = options.units > 0 ? options.units : m.profile.units();
  if (units <= 0) return absl::InvalidArgumentError("the fleet needs at least one unit");
  generator::PlanUnits(m, units, plan);
  INSDIAG_ASSIGN_OR_RETURN(auto interval_us, TestInterval(options, m, plan, units));
  generator::PlanTests(m, plan, interval_us);
  progress(absl::StrCat(
      "planned ", units, " units, ", plan.parts, " parts, ", plan.order.size(), " tests in ",
      absl::StrFormat(
          "%.1f", std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count()),
      " s (test interval ",
      absl::StrFormat("%.1f", static_cast<double>(interval_us) / kMicrosPerDay), " days)"));

  GeneratedFleet out;
  out.notes = m.notes;
  if (auto s =
          db->InTransaction([&] { return generator::WriteFleet(*db, m, plan, out, progress); });
      !s.ok()) {
    return s;
  }
  generator::FillTruth(m, plan, out);
  INSDIAG_RETURN_IF_ERROR(UpdateDerivedState(pool, *db, options, m.unit_type.name, progress));
  return out;
}

}  // namespace insdiag::kb
