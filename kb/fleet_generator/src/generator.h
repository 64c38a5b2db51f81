// The fleet generator's parts and the types they share (the model it draws
// from is described in insdiag/kb/fleet_generator.h):
//   model.cc            the model built from the data files
//   plan.cc             the plan of the fleet: units, parts, failures, tests,
//                       and what it makes true
//   evidence.cc         what a test measures and the analysis that reports it
//   copy_writer.cc      the plan written into the knowledge base with COPY
//   fleet_generator.cc  the entry points and the built-in fleet profiles
// Private to the fleet generator library.
#pragma once

#include <absl/functional/function_ref.h>
#include <absl/status/status.h>
#include <absl/status/statusor.h>

#include <cmath>
#include <cstdint>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

#include "insdiag/kb/fleet_generator.h"
#include "insdiag/kb/knowledge.h"
#include "insdiag/kb/pg.h"
#include "insdiag/v1/analyses.pb.h"
#include "insdiag/v1/knowledge.pb.h"

namespace insdiag::kb::generator {

inline constexpr std::int64_t kMicrosPerDay = 86'400'000'000LL;
inline constexpr double kMicrosPerYear = 365.25 * 86'400e6;  // Julian year
inline constexpr std::int64_t kNever = INT64_MAX;

// ---------------------------------------------------------------------------
// Random numbers: xoshiro256** (Blackman & Vigna, "Scrambled linear
// pseudorandom number generators", 2018) seeded through splitmix64, one
// stream per (purpose, index) so that every unit, batch and test draws the
// same numbers whatever is generated around it; normal deviates by
// Box–Muller. Portable: no std:: distributions (their algorithms differ
// between standard libraries).
inline std::uint64_t SplitMix(std::uint64_t& state) {
  std::uint64_t z = (state += 0x9E3779B97F4A7C15ULL);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}

enum Stream : std::uint64_t { kUnitStream = 1, kBatchStream, kScheduleStream, kTestStream, kSaltStream };

class Rng {
 public:
  Rng(std::uint64_t seed, Stream stream, std::uint64_t index) {
    std::uint64_t state = seed;
    state = SplitMix(state) ^ static_cast<std::uint64_t>(stream);
    state = SplitMix(state) ^ index;
    for (auto& word : s_) word = SplitMix(state);
  }
  std::uint64_t Next() {
    const std::uint64_t result = Rotl(s_[1] * 5, 7) * 9;
    const std::uint64_t t = s_[1] << 17;
    s_[2] ^= s_[0];
    s_[3] ^= s_[1];
    s_[1] ^= s_[2];
    s_[0] ^= s_[3];
    s_[2] ^= t;
    s_[3] = Rotl(s_[3], 45);
    return result;
  }
  double Uniform() { return (static_cast<double>(Next() >> 11) + 0.5) * 0x1.0p-53; }  // in (0, 1)
  double Normal() {
    const double u1 = Uniform(), u2 = Uniform();
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * std::numbers::pi * u2);
  }
  // Inverse CDF of Weibull(β, η): η (−ln U)^{1/β}.
  double Weibull(double shape, double scale) { return scale * std::pow(-std::log(Uniform()), 1.0 / shape); }
  double Exponential(double rate) { return -std::log(Uniform()) / rate; }

 private:
  static std::uint64_t Rotl(std::uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }
  std::uint64_t s_[4];
};

// ---------------------------------------------------------------------------
// The evidence the generated analyses carry.

// An identified parameter of the base model (nominal value > 0).
struct IdentifiedTerm {
  std::string name, unit, method;
  double nominal = 0, tolerance = 0;
  double healthy_sd = 0;  // of ln(v/v₀)
  int ageing = -1;        // index into the profile's ageing terms
  int parameter_id = 0;
};

// An effect candidate: with a tolerance (x in tolerance units) or without
// (x a standard score; its standard error from the profile).
struct EffectTerm {
  std::string name, family, unit;
  double tolerance = 0;  // 0: scored
  double std_error = 0;  // [SI]
  bool scored() const { return tolerance == 0; }
};

enum class TermKind { kIdentified, kEffect };

// How one signature term of a mode moves the evidence.
struct SignatureTargets {
  Signature term;
  TermKind kind = TermKind::kIdentified;
  std::vector<int> members;
};

struct ModeModel {
  std::string id;  // without the failureModes/ prefix
  int role = 0;
  double shape = 0, scale_hours = 0, expert_rate = 0;
  std::vector<SignatureTargets> terms;
};

struct Shift {
  TermKind kind;
  int index;
  double value;  // log ratio, tolerance units or standard score
};

struct Model {
  UnitType unit_type;
  std::string unit_type_id;
  DiagnosisSettings settings;
  v1::FleetProfile profile;
  std::vector<FailureMode> modes;
  std::vector<ModeModel> mode_models;
  std::vector<std::string> roles;
  std::vector<std::vector<int>> modes_of_role;
  std::vector<double> role_weight;  // Σ expert rates: the suspected role of a no-fault-found removal
  std::vector<IdentifiedTerm> identified;
  std::vector<EffectTerm> effects;
  std::int64_t start_us = 0, end_us = 0;
  double hours_per_year = 0;
  std::int64_t precursor_us = 0;
  std::uint64_t seed = 0;
  std::uint32_t salt = 0;
  std::string serial_prefix;
  std::string run_format;
  std::vector<std::string> notes;
};

// ---------------------------------------------------------------------------
// The plan of the fleet: every unit's life, before anything is written.

struct Failure {
  int part = 0;
  int mode = 0;
  std::int64_t time_us = 0;
  double hours = 0;
  bool realised = false;  // before the present (and the unit's withdrawal)
  std::vector<Shift> shifts;
  int test = -1;  // the unscheduled test that found it (realised)
};

struct Part {
  int role = 0;
  std::int64_t installed_us = 0, removed_us = kNever;
  double installed_hours = 0, removed_hours = 0;
  int failure = -1;  // its failure, realised or ahead
  bool withdrawn = false;
  std::int64_t module_id = 0;
};

struct NoFaultFound {
  int role = 0;
  std::int64_t time_us = 0;
  double hours = 0;
  int test = -1;
};

// kRetest: the return-to-service test after a repair or a removal without
// fault, when the record is closed.
enum class TestKind { kPeriodic, kFailure, kNoFaultFound, kRetest };

struct Test {
  std::int64_t time_us = 0;
  double hours = 0;
  TestKind kind = TestKind::kPeriodic;
  int event = -1;  // failure or no-fault-found index
  std::int64_t global = 0;  // position in time order: the run's and analysis's ids
  std::int64_t diagnosis = -1;
};

struct Batch {
  std::string name;
  std::vector<double> offset;  // per identified term, log ratio
  std::vector<double> ageing;  // per identified term, log ratio per year
};

struct UnitPlan {
  std::string serial;
  int batch = 0;
  std::int64_t unit_id = 0;
  std::int64_t commission_us = 0, end_us = 0;
  bool retired = false;
  double hours_per_us = 0;
  double end_hours = 0;
  std::vector<double> offset;  // per identified term
  std::vector<Part> parts;
  std::vector<Failure> failures;
  std::vector<NoFaultFound> no_fault_found;
  std::vector<Test> tests;
  double HoursAt(std::int64_t t) const { return hours_per_us * static_cast<double>(t - commission_us); }
  std::int64_t TimeAt(double hours) const { return commission_us + static_cast<std::int64_t>(hours / hours_per_us); }
};

struct Plan {
  std::vector<Batch> batches;
  std::vector<UnitPlan> units;
  // (unit, test) in time order.
  std::vector<std::pair<int, int>> order;
  std::int64_t interval_us = 0;
  std::int64_t parts = 0;
};

// What one test measured.
struct TestValues {
  std::vector<double> log_ratio;  // per identified term
  std::vector<double> effect_x;   // per effect term
  std::vector<bool> moving;       // per effect term: a drift moves it
  double nis_mean = 1;
  v1::AnalysisReport::Verdict verdict = v1::AnalysisReport::GOOD;
};

// An effect candidate as the engine reports it.
struct CandidateRow {
  int effect;
  double estimate, std_error, statistic, p_value, p_holm;
};

// ---------------------------------------------------------------------------
// model.cc

// The model of `options`' unit type from its data files; `roles` are the
// knowledge base's module roles.
absl::StatusOr<Model> BuildModel(const FleetGeneratorOptions& options, std::vector<std::string> roles);

// ---------------------------------------------------------------------------
// plan.cc

// Everything about `count` units but their periodic tests.
void PlanUnits(const Model& m, int count, Plan& plan);
// The tests: periodic at `interval_us`, plus one per failure and per
// no-fault-found removal, each followed by a retest when the record closes.
void PlanTests(const Model& m, Plan& plan, std::int64_t interval_us);
// Whether a unit's test is diagnosed: its latest and every unscheduled one.
bool Diagnosed(const UnitPlan& u, std::size_t test);
// From a failure or removal to its record's closing.
std::int64_t RecordDelay(const Model& m);
// What the plan makes true of the fleet, for tests and the tool's summary.
void FillTruth(const Model& m, const Plan& plan, GeneratedFleet& out);

// ---------------------------------------------------------------------------
// evidence.cc

// The share of a failure's signature change a test sees `ahead_us` before it.
double PrecursorShare(const Model& m, std::int64_t ahead_us);
// What a unit's test measures (the same every call: its own random stream).
TestValues Measure(const Model& m, const Plan& plan, std::size_t unit, std::size_t test);
// The candidates a test's analysis carries, most significant first: every
// effect when `all`, else the moving ones.
std::vector<CandidateRow> Candidates(const Model& m, const TestValues& v, bool all);
double IdentifiedValue(const IdentifiedTerm& t, double log_ratio);
double IdentifiedStdError(const Model& m, const IdentifiedTerm& t, double value);
// The report of a test's analysis, as the diagnosis reads it.
v1::AnalysisReport ReportOf(const Model& m, const TestValues& v);

// ---------------------------------------------------------------------------
// copy_writer.cc

// Writes the planned fleet (ids assigned here) with COPY inside the caller's
// transaction, counting what it wrote into `out`; `progress` hears each table.
absl::Status WriteFleet(Connection& db, const Model& m, Plan& plan, GeneratedFleet& out,
                        absl::FunctionRef<void(const std::string&)> progress);

}  // namespace insdiag::kb::generator
