// insdiag-fleet — writes a realistic fleet history into a knowledge base
// (insdiag/kb/fleet_generator.h, docs/FLEET.md): applies the built-in migrations,
// seeds the built-in unit types and failure modes, generates the fleet with
// COPY in one transaction, analyses the tables and refreshes the fleet views.
// Progress on standard error, a summary on standard output.
// Exit status: 0 ok, 1 refused or failed, 2 bad usage.
#include <CLI/CLI.hpp>
#include <absl/strings/str_cat.h>
#include <absl/time/time.h>

#include <chrono>
#include <cstdlib>
#include <iostream>

#include "insdiag/benchrun/bench_run_validation.h"
#include "insdiag/kb/connection_pool.h"
#include "insdiag/kb/fleet_generator.h"
#include "insdiag/kb/migrations.h"

namespace {

int Fail(const absl::Status& status) {
  std::cerr << "insdiag-fleet: " << absl::StatusCodeToString(status.code()) << ": " << status.message() << "\n";
  return 1;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"insdiag-fleet — write a generated fleet history (units, modules, tests, analyses, failures, "
               "diagnoses) into an insdiag knowledge base"};
  std::string database_url;
  std::string end_time;
  insdiag::kb::FleetGeneratorOptions options;
  app.add_option("--database-url", database_url, "PostgreSQL of the knowledge base (libpq URL)")
      ->envname("INSDIAG_DATABASE_URL")
      ->required();
  app.add_option("--unit-type", options.unit_type, "Unit type with built-in failure modes and fleet profile")
      ->capture_default_str();
  app.add_option("--units", options.units, "Units in the fleet (default: the profile's, 300 for INS-2000)");
  app.add_option("--analyses", options.analyses,
                 "Periodic analyses in the whole fleet: sets the test interval (default: the profile's interval)");
  app.add_option("--seed", options.seed, "Random seed: the same seed and end time give the same fleet")
      ->capture_default_str();
  app.add_option("--end-time", end_time, "The present of the history, YYYY-MM-DD or RFC 3339 (default: today, UTC)");
  app.add_option("--years", options.history_years, "Years of history (default: the profile's)");
  app.add_option("--hours-per-year", options.operating_hours_per_year,
                 "Median operating hours of a unit per year (default: the profile's)");
  app.add_option("--serial-prefix", options.serial_prefix, "Serials are PREFIX-n (default: G<seed>)");
  bool no_refine = false, no_refresh = false;
  app.add_flag("--no-refine", no_refine, "Do not refine the failure modes' signatures from the generated cases");
  app.add_flag("--no-refresh", no_refresh, "Do not refresh the fleet statistics' materialised views");
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& help) {
    return app.exit(help);
  } catch (const CLI::ParseError& error) {
    app.exit(error);
    return 2;
  }
  if (!end_time.empty()) {
    absl::Time t;
    std::string error;
    if (!absl::ParseTime("%Y-%m-%d", end_time, absl::UTCTimeZone(), &t, &error) &&
        !absl::ParseTime(absl::RFC3339_full, end_time, &t, &error)) {
      std::cerr << "insdiag-fleet: --end-time: '" << end_time << "' is neither YYYY-MM-DD nor RFC 3339\n";
      return 2;
    }
    options.end_time_micros = absl::ToUnixMicros(t);
  }
  options.run_format = std::string(insdiag::benchrun::kFormatV1);
  options.refine_signatures = !no_refine;
  options.refresh_views = !no_refresh;
  if (auto valid = options.Validate(); !valid.ok()) {
    std::cerr << "insdiag-fleet: " << valid.message() << "\n";
    return 2;
  }

  const auto start = std::chrono::steady_clock::now();
  auto pool = insdiag::kb::ConnectionPool::Create({.database_url = database_url, .max_connections = 2});
  if (!pool.ok()) return Fail(pool.status());
  {
    auto lease = (*pool)->Acquire();
    if (!lease.ok()) return Fail(lease.status());
    auto applied = insdiag::kb::ApplyMigrations(**lease, insdiag::kb::EmbeddedMigrations());
    if (!applied.ok()) return Fail(applied.status());
  }
  auto fleet = insdiag::kb::GenerateFleet(**pool, options, [](const std::string& line) {
    std::cerr << "insdiag-fleet: " << line << std::endl;
  });
  if (!fleet.ok()) return Fail(fleet.status());
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  for (const auto& note : fleet->notes) std::cerr << "insdiag-fleet: note: " << note << "\n";
  std::cout << "units " << fleet->units << " (retired " << fleet->retired_units << ")\n"
            << "modules " << fleet->modules << "\n"
            << "runs " << fleet->runs << "\n"
            << "analyses " << fleet->analyses << " (test interval " << fleet->truth.test_interval_days << " days)\n"
            << "identified_parameters " << fleet->identified_parameters << "\n"
            << "effect_candidates " << fleet->effect_candidates << "\n"
            << "confirmed_failures " << fleet->confirmed_failures << "\n"
            << "no_fault_found " << fleet->no_fault_found << "\n"
            << "censored_records " << fleet->censored_records << "\n"
            << "diagnoses " << fleet->diagnoses << "\n"
            << "operating_hours " << fleet->truth.fleet_operating_hours << "\n"
            << "seconds " << seconds << "\n";
  return 0;
}
