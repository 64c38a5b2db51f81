#include "insdiag/kb/fleet_generator.h"

#include <absl/strings/match.h>
#include <absl/strings/str_cat.h>
#include <absl/strings/str_format.h>
#include <absl/strings/str_split.h>
#include <openssl/sha.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>

#include "copy_text.h"
#include "fleet_profile_data.h"
#include "insdiag/api/json.h"
#include "insdiag/api/unit_types.h"
#include "insdiag/kb/diagnosis.h"
#include "insdiag/kb/fleet_store.h"
#include "insdiag/kb/knowledge_store.h"
#include "store_util.h"

namespace insdiag::kb {
namespace {

using internal::CopyRow;
using internal::Uuid;

constexpr std::int64_t kMicrosPerDay = 86'400'000'000LL;
constexpr double kMicrosPerYear = 365.25 * 86'400e6;  // Julian year
constexpr std::size_t kCopyChunkBytes = 1 << 20;
constexpr std::int64_t kNever = INT64_MAX;

// ---------------------------------------------------------------------------
// Random numbers: xoshiro256** (Blackman & Vigna, "Scrambled linear
// pseudorandom number generators", 2018) seeded through splitmix64, one
// stream per (purpose, index) so that every unit, batch and test draws the
// same numbers whatever is generated around it; normal deviates by
// Box–Muller. Portable: no std:: distributions (their algorithms differ
// between standard libraries).
std::uint64_t SplitMix(std::uint64_t& state) {
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
  v1::Signature term;
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
  v1::UnitType unit_type;
  std::string unit_type_id;
  v1::DiagnosisSettings settings;
  v1::FleetProfile profile;
  std::vector<v1::FailureMode> modes;
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

// ---------------------------------------------------------------------------

bool GlobMatches(const std::string& pattern, const std::string& name) {
  const std::vector<std::string> p = absl::StrSplit(pattern, '.');
  const std::vector<std::string> n = absl::StrSplit(name, '.');
  if (p.size() != n.size()) return false;
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (p[i] != "*" && p[i] != n[i]) return false;
  }
  return true;
}

std::string FamilyOf(const std::string& name) { return name.substr(0, name.find('.')); }

std::string ModeId(const v1::FailureMode& mode) { return mode.name().substr(std::string("failureModes/").size()); }

absl::StatusOr<Model> BuildModel(const FleetGeneratorOptions& options, std::vector<std::string> roles) {
  Model m;
  auto unit_type = api::BuiltinUnitType(options.unit_type);
  if (!unit_type.ok()) return unit_type.status();
  m.unit_type = *unit_type;
  m.unit_type_id = m.unit_type.name().substr(std::string("unitTypes/").size());
  auto catalogue = BuiltinFailureModeCatalogue(m.unit_type_id);
  if (!catalogue.ok()) return catalogue.status();
  m.settings = catalogue->settings();
  auto modes = ExpandCatalogue(*catalogue);
  if (!modes.ok()) return modes.status();
  m.modes = *modes;
  if (options.profile) {
    m.profile = *options.profile;
  } else {
    auto profile = BuiltinFleetProfile(m.unit_type_id);
    if (!profile.ok()) return profile.status();
    m.profile = *profile;
  }
  const v1::FleetProfile& p = m.profile;
  if (p.history_years() <= 0 || p.batch_months() <= 0 || p.operating_hours_per_year() <= 0 ||
      p.test_interval_days() <= 0 || p.precursor_days() <= 0 || p.sample_rate_hz() <= 0 ||
      p.batch_variance_share() < 0 || p.measurement_variance_share() < 0 ||
      p.batch_variance_share() + p.measurement_variance_share() >= 1 || p.effect_std_error_tolerances() <= 0 ||
      p.operable_tolerances() < 1) {
    return absl::InvalidArgumentError(absl::StrCat("fleet profile of ", m.unit_type_id,
                                                   ": history, batches, usage, test interval, precursor window, "
                                                   "sample rate and effect error must be positive, the variance "
                                                   "shares below 1 together, operable tolerances at least 1"));
  }
  m.roles = std::move(roles);
  m.modes_of_role.assign(m.roles.size(), {});
  m.role_weight.assign(m.roles.size(), 0.0);

  for (const auto& n : m.unit_type.nominal()) {
    if (n.value() > 0) {
      IdentifiedTerm t;
      t.name = n.name();
      t.unit = n.unit();
      t.nominal = n.value();
      t.tolerance = n.tolerance();
      t.healthy_sd = m.settings.healthy_log_ratio_fraction() * std::log1p(n.tolerance() / n.value());
      // The engine identifies Gauss–Markov drifts by correlation processing,
      // noise densities by Allan variance.
      t.method = absl::StrContains(n.name(), "_gm.") ? "ACF" : "ALLAN";
      for (int a = 0; a < p.ageing_size(); ++a) {
        if (GlobMatches(p.ageing(a).parameter(), n.name())) t.ageing = a;
      }
      m.identified.push_back(std::move(t));
    } else {
      m.effects.push_back({n.name(), FamilyOf(n.name()), n.unit(), n.tolerance(), 0.0});
    }
  }
  // Effects without a tolerance that a signature scores (standard scores).
  for (const auto& mode : m.modes) {
    for (const auto& s : mode.signature()) {
      if (s.scale() != "z" || absl::EndsWith(s.parameter(), ".*")) continue;
      const bool known = std::any_of(m.effects.begin(), m.effects.end(),
                                     [&](const EffectTerm& e) { return e.name == s.parameter(); });
      const auto se = p.effect_std_errors().find(FamilyOf(s.parameter()));
      if (known || se == p.effect_std_errors().end()) continue;
      m.effects.push_back({s.parameter(), FamilyOf(s.parameter()), "", 0.0, se->second});
    }
  }
  for (const auto& mode : m.modes) {
    ModeModel mm;
    mm.id = ModeId(mode);
    const auto role = std::find(m.roles.begin(), m.roles.end(), mode.module_role());
    if (role == m.roles.end()) {
      return absl::FailedPreconditionError(absl::StrCat(mode.name(), ": module role '", mode.module_role(),
                                                        "' is not in the knowledge base's module_roles"));
    }
    mm.role = static_cast<int>(role - m.roles.begin());
    mm.shape = mode.weibull_shape();
    mm.scale_hours = mode.weibull_scale_hours();
    mm.expert_rate = mode.expert_rate_per_million_hours() * 1e-6;
    for (const auto& s : mode.signature()) {
      SignatureTargets targets;
      targets.term = s;
      if (s.scale() == "log_ratio") {
        targets.kind = TermKind::kIdentified;
        for (std::size_t i = 0; i < m.identified.size(); ++i) {
          if (SignatureCovers(s.parameter(), m.identified[i].name)) targets.members.push_back(static_cast<int>(i));
        }
      } else {
        targets.kind = TermKind::kEffect;
        for (std::size_t i = 0; i < m.effects.size(); ++i) {
          const bool scale_fits = (s.scale() == "z") == m.effects[i].scored();
          if (scale_fits && SignatureCovers(s.parameter(), m.effects[i].name)) {
            targets.members.push_back(static_cast<int>(i));
          }
        }
      }
      if (targets.members.empty()) {
        m.notes.push_back(absl::StrCat(mode.name(), ": signature term ", s.parameter(), " (", s.scale(),
                                       ") has no measurable counterpart in ", m.unit_type.name(),
                                       " and the fleet profile: its failures show no precursor there"));
        continue;
      }
      mm.terms.push_back(std::move(targets));
    }
    m.modes_of_role[static_cast<std::size_t>(mm.role)].push_back(static_cast<int>(m.mode_models.size()));
    m.role_weight[static_cast<std::size_t>(mm.role)] += mm.expert_rate;
    m.mode_models.push_back(std::move(mm));
  }

  m.seed = options.seed;
  m.run_format = options.run_format;
  m.serial_prefix = options.serial_prefix.empty() ? absl::StrCat("G", options.seed) : options.serial_prefix;
  {
    std::uint64_t state = options.seed ^ static_cast<std::uint64_t>(AdvisoryLockKey(m.serial_prefix));
    m.salt = static_cast<std::uint32_t>(SplitMix(state) >> 32);
  }
  m.end_us = options.end_time_micros;
  if (m.end_us == 0) {
    const auto now = std::chrono::duration_cast<std::chrono::microseconds>(
                         std::chrono::system_clock::now().time_since_epoch())
                         .count();
    m.end_us = now - now % kMicrosPerDay;
  }
  const double years = options.history_years > 0 ? options.history_years : p.history_years();
  m.start_us = m.end_us - static_cast<std::int64_t>(years * kMicrosPerYear);
  m.hours_per_year = options.operating_hours_per_year > 0 ? options.operating_hours_per_year
                                                          : p.operating_hours_per_year();
  m.precursor_us = static_cast<std::int64_t>(p.precursor_days() * static_cast<double>(kMicrosPerDay));
  return m;
}

std::string BatchName(internal::YearMonth month, int batch_months) {
  if (batch_months == 3) return absl::StrCat(month.year, "Q", (month.month - 1) / 3 + 1);
  return absl::StrCat(month.year, "-", month.month < 10 ? "0" : "", month.month);
}

// The shifts of one failure's signature at its full size.
std::vector<Shift> DrawShifts(const ModeModel& mode, Rng& rng) {
  std::vector<Shift> shifts;
  const auto sign = [&](v1::Signature::Direction d) {
    if (d == v1::Signature::UP) return 1.0;
    if (d == v1::Signature::DOWN) return -1.0;
    return rng.Uniform() < 0.5 ? 1.0 : -1.0;
  };
  for (const auto& t : mode.terms) {
    const v1::Signature& s = t.term;
    if (s.common() && t.members.size() > 1) {
      const double value = sign(s.direction()) * (s.change() + s.spread() * rng.Normal());
      for (int member : t.members) shifts.push_back({t.kind, member, value});
      continue;
    }
    const double q = s.fraction() > 0 ? std::min(s.fraction(), 1.0) : 1.0;
    for (int member : t.members) {
      if (rng.Uniform() >= q) continue;
      shifts.push_back({t.kind, member, sign(s.direction()) * (s.change() + s.spread() * rng.Normal())});
    }
  }
  return shifts;
}

// Everything about the units but their periodic tests.
void PlanUnits(const Model& m, int count, Plan& plan) {
  const v1::FleetProfile& p = m.profile;
  std::map<std::string, int> batch_index;
  const double hours_per_us = 1.0 / kMicrosPerYear;  // × hours per year
  const double unit_sd = std::sqrt(1.0 - p.batch_variance_share() - p.measurement_variance_share());
  const double batch_sd = std::sqrt(p.batch_variance_share());
  const int width = std::max<int>(5, static_cast<int>(std::to_string(count).size()));
  plan.units.resize(static_cast<std::size_t>(count));
  for (int i = 0; i < count; ++i) {
    Rng rng(m.seed, kUnitStream, static_cast<std::uint64_t>(i));
    UnitPlan& u = plan.units[static_cast<std::size_t>(i)];
    const std::string number = std::to_string(i + 1);
    u.serial = absl::StrCat(m.serial_prefix, "-", std::string(static_cast<std::size_t>(width) - number.size(), '0'),
                            number);
    const double position = (static_cast<double>(i) + rng.Uniform()) / static_cast<double>(count);
    u.commission_us = m.start_us + static_cast<std::int64_t>(position * static_cast<double>(m.end_us - m.start_us));
    u.hours_per_us = m.hours_per_year * std::exp(p.operating_hours_log_sd() * rng.Normal()) * hours_per_us;
    u.end_us = m.end_us;
    if (p.retirement_per_year() > 0) {
      const double retire_us = rng.Exponential(p.retirement_per_year()) * kMicrosPerYear;
      if (retire_us < static_cast<double>(m.end_us - u.commission_us)) {
        u.end_us = u.commission_us + static_cast<std::int64_t>(retire_us);
        u.retired = true;
      }
    }
    u.end_hours = u.HoursAt(u.end_us);

    // The production batch: the commissioning period.
    const internal::YearMonth month = internal::YearMonthOf(u.commission_us);
    const int month_index = month.year * 12 + month.month - 1;
    const int first = month_index - month_index % p.batch_months();
    const std::string name = BatchName({first / 12, first % 12 + 1}, p.batch_months());
    auto [it, added] = batch_index.emplace(name, static_cast<int>(plan.batches.size()));
    if (added) {
      Rng batch_rng(m.seed, kBatchStream, static_cast<std::uint64_t>(first));
      Batch b;
      b.name = name;
      for (const auto& t : m.identified) {
        b.offset.push_back(batch_sd * t.healthy_sd * batch_rng.Normal());
        const double z = batch_rng.Normal();
        b.ageing.push_back(t.ageing < 0 ? 0.0
                                        : p.ageing(t.ageing).log_ratio_per_year() +
                                              p.ageing(t.ageing).batch_sd_per_year() * z);
      }
      plan.batches.push_back(std::move(b));
    }
    u.batch = it->second;
    for (const auto& t : m.identified) u.offset.push_back(unit_sd * t.healthy_sd * rng.Normal());

    // Parts and their lives, role by role (competing risks among the role's modes).
    for (std::size_t role = 0; role < m.roles.size(); ++role) {
      double installed_hours = 0;
      std::int64_t installed_us = u.commission_us;
      while (true) {
        Part part;
        part.role = static_cast<int>(role);
        part.installed_hours = installed_hours;
        part.installed_us = installed_us;
        double life = INFINITY;
        int mode = -1;
        for (int candidate : m.modes_of_role[role]) {
          const ModeModel& mm = m.mode_models[static_cast<std::size_t>(candidate)];
          const double t = rng.Weibull(mm.shape, mm.scale_hours);
          if (t < life) {
            life = t;
            mode = candidate;
          }
        }
        const int part_index = static_cast<int>(u.parts.size());
        if (mode >= 0) {
          Failure f;
          f.part = part_index;
          f.mode = mode;
          f.hours = installed_hours + life;
          f.realised = f.hours < u.end_hours;
          f.time_us = f.realised ? u.TimeAt(f.hours)
                                 : u.commission_us + static_cast<std::int64_t>(std::min(f.hours / u.hours_per_us, 1e17));
          f.shifts = DrawShifts(m.mode_models[static_cast<std::size_t>(mode)], rng);
          part.failure = static_cast<int>(u.failures.size());
          u.failures.push_back(std::move(f));
        }
        const Failure* failure = part.failure >= 0 ? &u.failures[static_cast<std::size_t>(part.failure)] : nullptr;
        if (failure != nullptr && failure->realised) {
          part.removed_us = failure->time_us;
          part.removed_hours = failure->hours;
          u.parts.push_back(part);
          installed_hours = failure->hours;
          installed_us = failure->time_us;
          continue;
        }
        if (u.retired) {
          part.removed_us = u.end_us;
          part.removed_hours = u.end_hours;
          part.withdrawn = true;
        }
        u.parts.push_back(part);
        break;
      }
    }
    // Removals on suspicion: a Poisson process in operating hours.
    double total_weight = 0;
    for (double w : m.role_weight) total_weight += w;
    if (p.no_fault_found_per_million_hours() > 0 && total_weight > 0) {
      double h = rng.Exponential(p.no_fault_found_per_million_hours() * 1e-6);
      while (h < u.end_hours) {
        double pick = rng.Uniform() * total_weight;
        int role = 0;
        while (role + 1 < static_cast<int>(m.role_weight.size()) && pick >= m.role_weight[static_cast<std::size_t>(role)]) {
          pick -= m.role_weight[static_cast<std::size_t>(role)];
          ++role;
        }
        u.no_fault_found.push_back({role, u.TimeAt(h), h, -1});
        h += rng.Exponential(p.no_fault_found_per_million_hours() * 1e-6);
      }
    }
    plan.parts += static_cast<std::int64_t>(u.parts.size());
  }
}

std::int64_t RecordDelay(const Model& m) {
  return static_cast<std::int64_t>(m.profile.record_delay_days() * static_cast<double>(kMicrosPerDay));
}

// The tests: periodic at `interval`, plus one per failure and per
// no-fault-found removal, each followed by a retest when the record closes.
void PlanTests(const Model& m, Plan& plan, std::int64_t interval_us) {
  plan.interval_us = interval_us;
  const double jitter = std::clamp(m.profile.test_interval_jitter(), 0.0, 0.9);
  for (std::size_t i = 0; i < plan.units.size(); ++i) {
    UnitPlan& u = plan.units[i];
    Rng rng(m.seed, kScheduleStream, i);
    for (std::int64_t t = u.commission_us; t < u.end_us;) {
      u.tests.push_back({t, u.HoursAt(t), TestKind::kPeriodic, -1, 0, -1});
      t += static_cast<std::int64_t>(static_cast<double>(interval_us) * (1.0 + jitter * (2.0 * rng.Uniform() - 1.0)));
    }
    const auto retest = [&](std::int64_t t) {
      const std::int64_t after = t + RecordDelay(m);
      if (after < u.end_us) u.tests.push_back({after, u.HoursAt(after), TestKind::kRetest, -1, 0, -1});
    };
    for (std::size_t f = 0; f < u.failures.size(); ++f) {
      if (u.failures[f].realised) {
        u.tests.push_back({u.failures[f].time_us, u.failures[f].hours, TestKind::kFailure, static_cast<int>(f), 0, -1});
        retest(u.failures[f].time_us);
      }
    }
    for (std::size_t n = 0; n < u.no_fault_found.size(); ++n) {
      const auto& e = u.no_fault_found[n];
      u.tests.push_back({e.time_us, e.hours, TestKind::kNoFaultFound, static_cast<int>(n), 0, -1});
      retest(e.time_us);
    }
    std::stable_sort(u.tests.begin(), u.tests.end(), [](const Test& a, const Test& b) { return a.time_us < b.time_us; });
    for (std::size_t t = 0; t < u.tests.size(); ++t) {
      const Test& test = u.tests[t];
      if (test.kind == TestKind::kFailure) u.failures[static_cast<std::size_t>(test.event)].test = static_cast<int>(t);
      if (test.kind == TestKind::kNoFaultFound) {
        u.no_fault_found[static_cast<std::size_t>(test.event)].test = static_cast<int>(t);
      }
    }
  }
  std::size_t total = 0;
  for (const auto& u : plan.units) total += u.tests.size();
  plan.order.clear();
  plan.order.reserve(total);
  for (std::size_t i = 0; i < plan.units.size(); ++i) {
    for (std::size_t t = 0; t < plan.units[i].tests.size(); ++t) plan.order.emplace_back(static_cast<int>(i), static_cast<int>(t));
  }
  std::sort(plan.order.begin(), plan.order.end(), [&](const auto& a, const auto& b) {
    const std::int64_t ta = plan.units[static_cast<std::size_t>(a.first)].tests[static_cast<std::size_t>(a.second)].time_us;
    const std::int64_t tb = plan.units[static_cast<std::size_t>(b.first)].tests[static_cast<std::size_t>(b.second)].time_us;
    return ta != tb ? ta < tb : a < b;
  });
  for (std::size_t g = 0; g < plan.order.size(); ++g) {
    plan.units[static_cast<std::size_t>(plan.order[g].first)].tests[static_cast<std::size_t>(plan.order[g].second)].global =
        static_cast<std::int64_t>(g);
  }
}

bool Diagnosed(const UnitPlan& u, std::size_t test) {
  const TestKind kind = u.tests[test].kind;
  return test + 1 == u.tests.size() || kind == TestKind::kFailure || kind == TestKind::kNoFaultFound;
}

// Two-sided normal p-value of a standard score.
double PValue(double z) { return std::erfc(std::abs(z) / std::numbers::sqrt2); }

// The share of a failure's signature change a test sees `ahead_us` before it.
double PrecursorShare(const Model& m, std::int64_t ahead_us) {
  if (ahead_us < 0 || ahead_us >= m.precursor_us) return 0.0;
  const double elapsed = 1.0 - static_cast<double>(ahead_us) / static_cast<double>(m.precursor_us);
  return std::pow(elapsed, m.profile.precursor_exponent());
}

TestValues Measure(const Model& m, const Plan& plan, std::size_t unit, std::size_t test) {
  const UnitPlan& u = plan.units[unit];
  const Test& t = u.tests[test];
  const Batch& b = plan.batches[static_cast<std::size_t>(u.batch)];
  const v1::FleetProfile& p = m.profile;
  TestValues v;
  v.log_ratio.assign(m.identified.size(), 0.0);
  v.effect_x.assign(m.effects.size(), 0.0);
  v.moving.assign(m.effects.size(), false);
  // Drifts of parts failing within the precursor window.
  for (const auto& f : u.failures) {
    const Part& part = u.parts[static_cast<std::size_t>(f.part)];
    if (t.time_us < part.installed_us || t.time_us > f.time_us || f.time_us - t.time_us >= m.precursor_us) continue;
    const double share = PrecursorShare(m, f.time_us - t.time_us);
    for (const auto& s : f.shifts) {
      if (s.kind == TermKind::kIdentified) {
        v.log_ratio[static_cast<std::size_t>(s.index)] += share * s.value;
      } else {
        v.effect_x[static_cast<std::size_t>(s.index)] += share * s.value;
        v.moving[static_cast<std::size_t>(s.index)] = true;
      }
    }
  }
  Rng rng(m.seed, kTestStream, (static_cast<std::uint64_t>(unit) << 24) | test);
  const double age_years = static_cast<double>(t.time_us - u.commission_us) / kMicrosPerYear;
  const double measurement_sd = std::sqrt(p.measurement_variance_share());
  double worst = 0, excess = 0;
  for (std::size_t i = 0; i < m.identified.size(); ++i) {
    const IdentifiedTerm& term = m.identified[i];
    v.log_ratio[i] += b.offset[i] + u.offset[i] + b.ageing[i] * age_years + measurement_sd * term.healthy_sd * rng.Normal();
    const double tolerances = std::abs(term.nominal * std::expm1(v.log_ratio[i])) / term.tolerance;
    worst = std::max(worst, tolerances);
    excess += std::pow(std::max(tolerances - 1.0, 0.0), 2);
  }
  const double m_tests = static_cast<double>(m.effects.size());
  bool significant = false;
  for (std::size_t i = 0; i < m.effects.size(); ++i) {
    const EffectTerm& e = m.effects[i];
    v.effect_x[i] += (e.scored() ? m.settings.healthy_z_sd() : m.settings.healthy_tolerance_sd()) * rng.Normal();
    if (e.scored()) {
      significant = significant || PValue(v.effect_x[i]) * m_tests < m.settings.significance_level();
    } else {
      worst = std::max(worst, std::abs(v.effect_x[i]));
      excess += std::pow(std::max(std::abs(v.effect_x[i]) - 1.0, 0.0), 2);
    }
  }
  v.verdict = worst <= 1.0 && !significant         ? v1::AnalysisReport::GOOD
              : worst <= p.operable_tolerances() ? v1::AnalysisReport::OPERABLE
                                                   : v1::AnalysisReport::FAULTY;
  const double terms = static_cast<double>(m.identified.size() + m.effects.size());
  v.nis_mean = (1.0 + p.nis_mean_sd() * rng.Normal()) * (1.0 + excess / std::max(terms, 1.0));
  return v;
}

// An effect candidate as the engine reports it.
struct CandidateRow {
  int effect;
  double estimate, std_error, statistic, p_value, p_holm;
};

// The candidates a test's analysis carries: every effect for the analyses
// that are diagnosed, else the moving ones. Holm's adjustment over all the
// unit type's effects, the unwritten ones (not moving) taken as less
// significant than the written.
std::vector<CandidateRow> Candidates(const Model& m, const TestValues& v, bool all) {
  std::vector<CandidateRow> rows;
  for (std::size_t i = 0; i < m.effects.size(); ++i) {
    if (!all && !v.moving[i]) continue;
    const EffectTerm& e = m.effects[i];
    CandidateRow r;
    r.effect = static_cast<int>(i);
    r.std_error = e.scored() ? e.std_error : m.profile.effect_std_error_tolerances() * e.tolerance;
    const double z = e.scored() ? v.effect_x[i] : v.effect_x[i] / m.profile.effect_std_error_tolerances();
    r.estimate = z * r.std_error;
    r.statistic = z * z;
    r.p_value = PValue(z);
    rows.push_back(r);
  }
  std::sort(rows.begin(), rows.end(), [](const CandidateRow& a, const CandidateRow& b) { return a.p_value < b.p_value; });
  double running = 0;
  for (std::size_t k = 0; k < rows.size(); ++k) {
    running = std::max(running, std::min(1.0, static_cast<double>(m.effects.size() - k) * rows[k].p_value));
    rows[k].p_holm = running;
  }
  return rows;
}

double IdentifiedValue(const IdentifiedTerm& t, double log_ratio) { return t.nominal * std::exp(log_ratio); }
double IdentifiedStdError(const Model& m, const IdentifiedTerm& t, double value) {
  return value * std::sqrt(m.profile.measurement_variance_share()) * t.healthy_sd;
}

v1::AnalysisReport ReportOf(const Model& m, const TestValues& v) {
  v1::AnalysisReport report;
  report.set_verdict(v.verdict);
  report.set_nis_mean(v.nis_mean);
  for (std::size_t i = 0; i < m.identified.size(); ++i) {
    const IdentifiedTerm& t = m.identified[i];
    auto* p = report.add_identified();
    p->set_name(t.name);
    p->set_value(IdentifiedValue(t, v.log_ratio[i]));
    p->set_std_error(IdentifiedStdError(m, t, p->value()));
    v1::IdentifiedParameter::Method method = v1::IdentifiedParameter::METHOD_UNSPECIFIED;
    v1::IdentifiedParameter::Method_Parse(t.method, &method);
    p->set_method(method);
    p->set_unit(t.unit);
    p->set_a_priori(t.nominal);
  }
  for (const auto& r : Candidates(m, v, true)) {
    const EffectTerm& e = m.effects[static_cast<std::size_t>(r.effect)];
    auto* c = report.add_effect_candidates();
    c->set_name(e.name);
    c->set_family(e.family);
    c->set_unit(e.unit);
    c->set_source("SCORE");
    c->set_statistic(r.statistic);
    c->set_degrees_of_freedom(1);
    c->set_p_value(r.p_value);
    c->set_p_value_holm(r.p_holm);
    c->set_estimate(r.estimate);
    c->set_std_error(r.std_error);
    c->set_identifiable(true);
  }
  return report;
}

// ---------------------------------------------------------------------------
// Writing.

// Ids: {salt:8}-{kind:4}-8{index}-a{index}-{index}: one generation's ids share
// a prefix and increase with the index (ids of one kind append to their index).
Uuid MakeId(std::uint32_t salt, std::uint16_t kind, std::uint64_t index) {
  Uuid id;
  id.hi = (static_cast<std::uint64_t>(salt) << 32) | (static_cast<std::uint64_t>(kind) << 16) | 0x8000U |
          ((index >> 60) & 0xfffU);
  id.lo = 0xa000000000000000ULL | (index & 0x0fffffffffffffffULL);
  return id;
}

enum IdKind : std::uint16_t { kRunIds = 1, kAnalysisIds, kRecordIds, kDiagnosisIds };

absl::StatusOr<std::int64_t> CopyItems(Connection& db, std::string_view sql, std::size_t count,
                                       absl::FunctionRef<void(std::size_t, std::string&)> emit) {
  std::size_t next = 0;
  return db.CopyIn(sql, [&](std::string& buffer) {
    while (next < count && buffer.size() < kCopyChunkBytes) emit(next++, buffer);
    return next < count;
  });
}

absl::StatusOr<std::vector<std::int64_t>> ReserveIds(Connection& db, const char* table, const char* column,
                                                     std::int64_t count) {
  auto rows = db.Exec("SELECT nextval(pg_get_serial_sequence($1, $2)) FROM generate_series(1, $3)",
                      {Param::Text(table), Param::Text(column), Param::Int(count)});
  if (!rows.ok()) return rows.status();
  std::vector<std::int64_t> ids;
  ids.reserve(static_cast<std::size_t>(count));
  for (int r = 0; r < rows->rows(); ++r) ids.push_back(internal::IntOr0(*rows, r, 0));
  return ids;
}

// The foreign keys of the tables the generator fills are dropped for the
// load and added back (validated in one join per key) before commit: per-row
// checks would cost minutes for millions of rows. The tables are locked
// meanwhile (ACCESS EXCLUSIVE, until the transaction ends).
constexpr char kLoadedTables[] =
    "{modules,runs,analyses,identified_parameters,effect_candidates,diagnoses,diagnosis_candidates,failure_records}";

absl::StatusOr<std::vector<std::string>> DropForeignKeys(Connection& db) {
  auto keys = db.Exec(
      "SELECT format('ALTER TABLE %s DROP CONSTRAINT %I', conrelid::regclass, conname), "
      "format('ALTER TABLE %s ADD CONSTRAINT %I %s', conrelid::regclass, conname, pg_get_constraintdef(oid)) "
      "FROM pg_constraint WHERE contype = 'f' AND conrelid = ANY($1::regclass[]) ORDER BY conrelid, conname",
      {Param::Text(kLoadedTables)});
  if (!keys.ok()) return keys.status();
  std::vector<std::string> restore;
  for (int r = 0; r < keys->rows(); ++r) {
    if (auto s = db.ExecScript(keys->String(r, 0)); !s.ok()) return s;
    restore.push_back(keys->String(r, 1));
  }
  return restore;
}

std::string EmptyDigest() {
  unsigned char digest[SHA256_DIGEST_LENGTH];
  SHA256(nullptr, 0, digest);
  std::string hex;
  for (unsigned char c : digest) absl::StrAppend(&hex, absl::Hex(c, absl::kZeroPad2));
  return hex;
}

const char* KindName(TestKind kind) {
  switch (kind) {
    case TestKind::kPeriodic: return "periodic";
    case TestKind::kFailure: return "failure";
    case TestKind::kNoFaultFound: return "no fault found";
    case TestKind::kRetest: return "retest after repair";
  }
  return "";
}

class Writer {
 public:
  Writer(Connection& db, const Model& m, Plan& plan, GeneratedFleet& out,
         absl::FunctionRef<void(const std::string&)> progress)
      : db_(db), m_(m), plan_(plan), out_(out), progress_(progress) {}

  absl::Status WriteAll();

 private:
  // Runs one COPY, reporting its rows and time.
  absl::Status Copy(const std::string& what, std::string_view sql, std::size_t items,
                    absl::FunctionRef<void(std::size_t, std::string&)> emit, std::int64_t* count);
  absl::Status Prepare();
  void EmitUnit(std::size_t i, std::string& buffer) const;
  void EmitModules(std::size_t i, std::string& buffer) const;
  void EmitRun(std::size_t g, std::string& buffer) const;
  void EmitAnalysis(std::size_t g, std::string& buffer) const;
  void EmitIdentified(std::size_t g, std::string& buffer) const;
  void EmitCandidates(std::size_t g, std::string& buffer) const;
  void EmitDiagnosis(std::size_t d, std::string& buffer, std::string& candidates) const;
  void EmitRecords(std::size_t i, std::string& buffer) const;

  const Test& TestAt(std::size_t g) const {
    const auto [unit, test] = plan_.order[g];
    return plan_.units[static_cast<std::size_t>(unit)].tests[static_cast<std::size_t>(test)];
  }
  Uuid RunId(const Test& t) const { return MakeId(m_.salt, kRunIds, static_cast<std::uint64_t>(t.global)); }
  Uuid AnalysisId(const Test& t) const { return MakeId(m_.salt, kAnalysisIds, static_cast<std::uint64_t>(t.global)); }
  Uuid DiagnosisId(std::int64_t d) const { return MakeId(m_.salt, kDiagnosisIds, static_cast<std::uint64_t>(d)); }
  v1::Diagnosis DiagnosisOf(std::size_t d) const;

  Connection& db_;
  const Model& m_;
  Plan& plan_;
  GeneratedFleet& out_;
  absl::FunctionRef<void(const std::string&)> progress_;
  std::vector<int> parameter_ids_;
  std::vector<std::pair<int, int>> diagnosed_;  // (unit, test) of each diagnosis, in diagnosis order
  std::vector<std::uint64_t> first_record_;     // per unit: index of its first failure record
  PriorInputs prior_;
  std::string digest_;
  std::string generated_note_;
};

absl::Status Writer::Copy(const std::string& what, std::string_view sql, std::size_t items,
                          absl::FunctionRef<void(std::size_t, std::string&)> emit, std::int64_t* count) {
  const auto start = std::chrono::steady_clock::now();
  auto rows = CopyItems(db_, sql, items, emit);
  if (!rows.ok()) return rows.status();
  if (count != nullptr) *count = *rows;
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  progress_(absl::StrCat(what, ": ", *rows, " rows in ", absl::StrFormat("%.1f", seconds), " s"));
  return absl::OkStatus();
}

absl::Status Writer::Prepare() {
  std::vector<std::string> names;
  for (const auto& t : m_.identified) names.push_back(t.name);
  const std::string literal = internal::TextArrayLiteral(names);
  auto inserted = db_.Exec("INSERT INTO parameter_names (name) SELECT unnest($1::text[]) ON CONFLICT DO NOTHING",
                           {Param::Text(literal)});
  if (!inserted.ok()) return inserted.status();
  auto rows = db_.Exec("SELECT name, parameter_id FROM parameter_names WHERE name = ANY($1::text[])",
                       {Param::Text(literal)});
  if (!rows.ok()) return rows.status();
  std::map<std::string, int> ids;
  for (int r = 0; r < rows->rows(); ++r) ids[rows->String(r, 0)] = static_cast<int>(internal::IntOr0(*rows, r, 1));
  for (const auto& t : m_.identified) parameter_ids_.push_back(ids[t.name]);

  auto unit_ids = ReserveIds(db_, "units", "unit_id", static_cast<std::int64_t>(plan_.units.size()));
  if (!unit_ids.ok()) return unit_ids.status();
  auto module_ids = ReserveIds(db_, "modules", "module_id", plan_.parts);
  if (!module_ids.ok()) return module_ids.status();
  std::size_t next_module = 0;
  std::uint64_t next_record = 0;
  for (std::size_t i = 0; i < plan_.units.size(); ++i) {
    UnitPlan& u = plan_.units[i];
    u.unit_id = (*unit_ids)[i];
    for (auto& part : u.parts) part.module_id = (*module_ids)[next_module++];
    first_record_.push_back(next_record);
    for (const auto& f : u.failures) next_record += f.realised ? 1 : 0;
    next_record += u.no_fault_found.size();
    if (u.retired) {
      for (const auto& part : u.parts) next_record += part.withdrawn ? 1 : 0;
    }
  }
  // Diagnoses: every unit's latest test and every unscheduled one, their
  // priors from the generated fleet's exposure and confirmed failures.
  for (std::size_t i = 0; i < plan_.units.size(); ++i) {
    UnitPlan& u = plan_.units[i];
    prior_.fleet_exposure_hours += u.end_hours;
    for (const auto& f : u.failures) {
      if (f.realised) ++prior_.confirmed_failures[m_.modes[static_cast<std::size_t>(f.mode)].name()];
    }
    for (std::size_t t = 0; t < u.tests.size(); ++t) {
      if (!Diagnosed(u, t)) continue;
      u.tests[t].diagnosis = static_cast<std::int64_t>(diagnosed_.size());
      diagnosed_.emplace_back(static_cast<int>(i), static_cast<int>(t));
    }
  }
  digest_ = EmptyDigest();
  generated_note_ = absl::StrCat("insdiag-fleet seed ", m_.seed, ": metadata only, no samples");
  return absl::OkStatus();
}

void Writer::EmitUnit(std::size_t i, std::string& buffer) const {
  const UnitPlan& u = plan_.units[i];
  CopyRow row(buffer);
  row.Int(u.unit_id).Text(u.serial).Text(m_.unit_type_id).Time(u.commission_us);
  row.Text(plan_.batches[static_cast<std::size_t>(u.batch)].name).Time(u.commission_us).Double(u.end_hours);
  if (u.retired) {
    row.Time(u.end_us);
  } else {
    row.Null();
  }
  row.End();
}

void Writer::EmitModules(std::size_t i, std::string& buffer) const {
  const UnitPlan& u = plan_.units[i];
  for (const Part& part : u.parts) {
    CopyRow row(buffer);
    row.Int(part.module_id).Int(u.unit_id).Text(m_.roles[static_cast<std::size_t>(part.role)]);
    row.Text(absl::StrCat("P", absl::Hex(m_.salt, absl::kZeroPad8), "-", part.module_id));
    row.Time(part.installed_us).Double(part.installed_hours);
    if (part.removed_us == kNever) {
      row.Null().Null().Null();
    } else if (part.withdrawn) {
      row.Time(part.removed_us).Double(part.removed_hours).Text("unit retired");
    } else {
      const Failure& f = u.failures[static_cast<std::size_t>(part.failure)];
      row.Time(part.removed_us).Double(part.removed_hours);
      row.Text(absl::StrCat("failed: ", m_.mode_models[static_cast<std::size_t>(f.mode)].id));
    }
    row.End();
  }
}

void Writer::EmitRun(std::size_t g, std::string& buffer) const {
  const UnitPlan& u = plan_.units[static_cast<std::size_t>(plan_.order[g].first)];
  const Test& t = TestAt(g);
  const v1::FleetProfile& p = m_.profile;
  CopyRow row(buffer);
  row.Id(RunId(t)).Int(u.unit_id).Text(m_.run_format).Text(u.serial).Text(m_.unit_type_id);
  row.Double(p.site_latitude_deg()).Double(p.site_longitude_deg()).Double(p.site_height_m());
  row.Text(absl::StrCat(R"([["generated",")", generated_note_, R"("],["test",")", KindName(t.kind),
                        R"("],["test_duration_s",")", p.test_duration_s(), R"("]])"));
  row.Bool(false).Int(0).Double(1.0 / p.sample_rate_hz()).Double(0).Double(0).Text(digest_);
  row.Time(t.time_us).Time(t.time_us);
  row.End();
}

void Writer::EmitAnalysis(std::size_t g, std::string& buffer) const {
  const auto [unit, test] = plan_.order[g];
  const UnitPlan& u = plan_.units[static_cast<std::size_t>(unit)];
  const Test& t = TestAt(g);
  const TestValues v = Measure(m_, plan_, static_cast<std::size_t>(unit), static_cast<std::size_t>(test));
  CopyRow row(buffer);
  row.Id(AnalysisId(t)).Id(RunId(t)).Int(u.unit_id).Text("SUCCEEDED").Int(1).Double(1).Text("done");
  row.Text(v1::AnalysisReport::Verdict_Name(v.verdict)).Double(v.nis_mean).Double(t.hours);
  row.Time(t.time_us).Time(t.time_us).Time(t.time_us).Time(t.time_us);
  row.End();
}

void Writer::EmitIdentified(std::size_t g, std::string& buffer) const {
  const auto [unit, test] = plan_.order[g];
  const Test& t = TestAt(g);
  const TestValues v = Measure(m_, plan_, static_cast<std::size_t>(unit), static_cast<std::size_t>(test));
  const Uuid id = AnalysisId(t);
  for (std::size_t i = 0; i < m_.identified.size(); ++i) {
    const IdentifiedTerm& term = m_.identified[i];
    const double value = IdentifiedValue(term, v.log_ratio[i]);
    CopyRow row(buffer);
    row.Id(id).Int(parameter_ids_[i]).Double(value).Double(IdentifiedStdError(m_, term, value)).Text(term.method);
    row.Double(term.nominal);
    row.End();
  }
}

void Writer::EmitCandidates(std::size_t g, std::string& buffer) const {
  const auto [unit, test] = plan_.order[g];
  const UnitPlan& u = plan_.units[static_cast<std::size_t>(unit)];
  const Test& t = TestAt(g);
  const TestValues v = Measure(m_, plan_, static_cast<std::size_t>(unit), static_cast<std::size_t>(test));
  const Uuid id = AnalysisId(t);
  for (const auto& r : Candidates(m_, v, Diagnosed(u, static_cast<std::size_t>(test)))) {
    const EffectTerm& e = m_.effects[static_cast<std::size_t>(r.effect)];
    CopyRow row(buffer);
    row.Id(id).Text(e.name).Text(e.family).Bool(false).Text("SCORE").Double(r.statistic).Int(1).Double(r.p_value);
    row.Double(r.p_holm).Double(r.estimate).Double(r.std_error).Text(e.unit).Bool(true);
    row.End();
  }
}

v1::Diagnosis Writer::DiagnosisOf(std::size_t d) const {
  const auto [unit, test] = diagnosed_[d];
  const UnitPlan& u = plan_.units[static_cast<std::size_t>(unit)];
  const Test& t = u.tests[static_cast<std::size_t>(test)];
  const v1::AnalysisReport report =
      ReportOf(m_, Measure(m_, plan_, static_cast<std::size_t>(unit), static_cast<std::size_t>(test)));
  PriorInputs prior = prior_;
  prior.exposure_hours = t.hours - (test > 0 ? u.tests[static_cast<std::size_t>(test) - 1].hours : 0.0);
  v1::Diagnosis diagnosis =
      Diagnose(EvidenceFromReport(report, m_.unit_type, m_.settings), m_.modes, m_.settings, prior);
  diagnosis.set_name(absl::StrCat("diagnoses/", internal::UuidText(DiagnosisId(t.diagnosis))));
  diagnosis.set_analysis(absl::StrCat("analyses/", internal::UuidText(AnalysisId(t))));
  diagnosis.set_unit(absl::StrCat("units/", u.serial));
  *diagnosis.mutable_create_time() = internal::TimestampOfMicros(t.time_us);
  return diagnosis;
}

// A diagnosis row, and its candidates' rows into `candidates` (a diagnosis
// costs ~1 ms to compute: once is enough).
void Writer::EmitDiagnosis(std::size_t d, std::string& buffer, std::string& candidates) const {
  const auto [unit, test] = diagnosed_[d];
  const UnitPlan& u = plan_.units[static_cast<std::size_t>(unit)];
  const Test& t = u.tests[static_cast<std::size_t>(test)];
  const v1::Diagnosis diagnosis = DiagnosisOf(d);
  int rank = 0;
  for (const auto& c : diagnosis.candidates()) {
    CopyRow row(candidates);
    row.Id(DiagnosisId(t.diagnosis)).Int(rank++).Text(c.module()).Text(c.failure_mode()).Double(c.probability());
    row.TextArray(std::vector<std::string>(c.evidence().begin(), c.evidence().end()));
    row.End();
  }
  const DiagnosisHeadline headline = HeadlineOf(diagnosis);
  std::string body;
  diagnosis.SerializeToString(&body);
  CopyRow row(buffer);
  row.Id(DiagnosisId(t.diagnosis)).Id(AnalysisId(t)).Int(u.unit_id).Double(headline.fault_probability);
  row.Text(headline.top ? headline.top->module() : "").Text(headline.top ? headline.top->failure_mode() : "");
  row.Double(headline.top ? headline.top->probability() : 0.0).Bytes(body);
  row.TextArray(std::vector<std::string>(diagnosis.notes().begin(), diagnosis.notes().end())).Time(t.time_us);
  row.End();
}

// Failure records of one unit: confirmed failures, removals without fault
// found, and a censored record per part withdrawn with a retired unit.
void Writer::EmitRecords(std::size_t i, std::string& buffer) const {
  const UnitPlan& u = plan_.units[i];
  const std::int64_t delay = RecordDelay(m_);
  std::uint64_t next = first_record_[i];
  const auto start = [&](std::int64_t module_id, const std::string& mode) -> CopyRow {
    CopyRow row(buffer);
    row.Id(MakeId(m_.salt, kRecordIds, next++)).Int(module_id).Int(u.unit_id);
    if (mode.empty()) {
      row.Null();
    } else {
      row.Text(mode);
    }
    return row;
  };
  for (const auto& f : u.failures) {
    if (!f.realised) continue;
    const Test& t = u.tests[static_cast<std::size_t>(f.test)];
    CopyRow row = start(u.parts[static_cast<std::size_t>(f.part)].module_id, m_.mode_models[static_cast<std::size_t>(f.mode)].id);
    row.Id(AnalysisId(t)).Id(DiagnosisId(t.diagnosis)).Time(f.time_us).Double(f.hours);
    row.Bool(true).Bool(false).Bool(false).Bool(true).Text("module replaced").Text("").Time(f.time_us + delay);
    row.End();
  }
  for (const auto& n : u.no_fault_found) {
    const Test& t = u.tests[static_cast<std::size_t>(n.test)];
    std::int64_t module_id = 0;
    for (const auto& part : u.parts) {
      if (part.role == n.role && part.installed_us <= n.time_us && n.time_us < part.removed_us) module_id = part.module_id;
    }
    CopyRow row = start(module_id, "");
    row.Id(AnalysisId(t)).Id(DiagnosisId(t.diagnosis)).Time(n.time_us).Double(n.hours);
    row.Bool(false).Bool(true).Bool(false).Bool(false).Text("none: no fault found, returned to service").Text("");
    row.Time(n.time_us + delay);
    row.End();
  }
  if (u.retired) {
    for (const auto& part : u.parts) {
      if (!part.withdrawn) continue;
      CopyRow row = start(part.module_id, "");
      row.Null().Null().Time(u.end_us).Double(u.end_hours);
      row.Bool(false).Bool(false).Bool(true).Bool(false).Text("").Text("unit retired").Time(u.end_us);
      row.End();
    }
  }
}

absl::Status Writer::WriteAll() {
  if (auto s = Prepare(); !s.ok()) return s;
  // Validating the keys joins millions of rows: give the joins memory.
  if (auto s = db_.ExecScript("SET LOCAL work_mem = '256MB'"); !s.ok()) return s;
  auto restore = DropForeignKeys(db_);
  if (!restore.ok()) return restore.status();
  const std::size_t tests = plan_.order.size();
  const std::size_t units = plan_.units.size();
  std::int64_t ignored = 0;
  std::string candidates;
  if (auto s = Copy("units",
                    "COPY units (unit_id, serial, unit_type, create_time, batch, commission_time, operating_hours, "
                    "retired_time) FROM STDIN",
                    units, [&](std::size_t i, std::string& b) { EmitUnit(i, b); }, &out_.units);
      !s.ok()) {
    return s.code() == absl::StatusCode::kAlreadyExists
               ? absl::AlreadyExistsError(absl::StrCat("serials ", m_.serial_prefix,
                                                       "-… are taken: choose another serial prefix (", s.message(),
                                                       ")"))
               : s;
  }
  if (auto s = Copy("modules",
                    "COPY modules (module_id, unit_id, role, part_serial, installed_time, installed_hours, "
                    "removed_time, removed_hours, removal_reason) FROM STDIN",
                    units, [&](std::size_t i, std::string& b) { EmitModules(i, b); }, &out_.modules);
      !s.ok()) {
    return s;
  }
  if (auto s = Copy("runs",
                    "COPY runs (run_id, unit_id, format, unit_serial, unit_type, site_latitude_deg, "
                    "site_longitude_deg, site_height_m, extra_metadata, has_temperature, sample_count, "
                    "nominal_interval_s, duration_s, first_t, sha256, create_time, test_time) FROM STDIN",
                    tests, [&](std::size_t g, std::string& b) { EmitRun(g, b); }, &out_.runs);
      !s.ok()) {
    return s;
  }
  if (auto s = Copy("analyses",
                    "COPY analyses (analysis_id, run_id, unit_id, state, attempts, progress_fraction, progress_stage, "
                    "verdict, nis_mean, unit_hours, create_time, update_time, start_time, end_time) FROM STDIN",
                    tests, [&](std::size_t g, std::string& b) { EmitAnalysis(g, b); }, &out_.analyses);
      !s.ok()) {
    return s;
  }
  if (auto s = Copy("identified parameters",
                    "COPY identified_parameters (analysis_id, parameter_id, value, std_error, method, a_priori) "
                    "FROM STDIN",
                    tests, [&](std::size_t g, std::string& b) { EmitIdentified(g, b); }, &out_.identified_parameters);
      !s.ok()) {
    return s;
  }
  if (auto s = Copy("effect candidates",
                    "COPY effect_candidates (analysis_id, name, family, per_family, source, statistic, "
                    "degrees_of_freedom, p_value, p_value_holm, estimate, std_error, unit, identifiable) FROM STDIN",
                    tests, [&](std::size_t g, std::string& b) { EmitCandidates(g, b); }, &out_.effect_candidates);
      !s.ok()) {
    return s;
  }
  if (auto s = Copy("diagnoses",
                    "COPY diagnoses (diagnosis_id, analysis_id, unit_id, fault_probability, top_module, "
                    "top_failure_mode, top_probability, body, notes, create_time) FROM STDIN",
                    diagnosed_.size(), [&](std::size_t d, std::string& b) { EmitDiagnosis(d, b, candidates); },
                    &out_.diagnoses);
      !s.ok()) {
    return s;
  }
  if (auto s = Copy("diagnosis candidates",
                    "COPY diagnosis_candidates (diagnosis_id, rank, module, failure_mode, probability, evidence) "
                    "FROM STDIN",
                    1, [&](std::size_t, std::string& b) { b.swap(candidates); }, &ignored);
      !s.ok()) {
    return s;
  }
  if (auto s = Copy("failure records",
                    "COPY failure_records (record_id, module_id, unit_id, failure_mode, analysis_id, diagnosis_id, "
                    "detected_time, operating_hours, confirmed, no_fault_found, censored, repaired, repair_action, "
                    "notes, record_time) FROM STDIN",
                    units, [&](std::size_t i, std::string& b) { EmitRecords(i, b); }, &ignored);
      !s.ok()) {
    return s;
  }
  // The diagnoses of failures and removals are resolved by their records.
  auto linked = db_.Exec(
      "UPDATE diagnoses d SET record_id = r.record_id FROM failure_records r "
      "WHERE r.diagnosis_id = d.diagnosis_id AND d.record_id IS NULL AND r.record_id >= $1::uuid AND r.record_id <= $2::uuid",
      {Param::Text(internal::UuidText(MakeId(m_.salt, kRecordIds, 0))),
       Param::Text(internal::UuidText(MakeId(m_.salt, kRecordIds, 0x0fffffffffffffffULL)))});
  if (!linked.ok()) return linked.status();
  const auto start = std::chrono::steady_clock::now();
  for (const auto& statement : *restore) {
    if (auto s = db_.ExecScript(statement); !s.ok()) return s;
  }
  progress_(absl::StrCat("validated ", restore->size(), " foreign keys in ",
                         absl::StrFormat("%.1f", std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count()),
                         " s"));
  for (const auto& u : plan_.units) {
    out_.retired_units += u.retired ? 1 : 0;
    for (const auto& f : u.failures) out_.confirmed_failures += f.realised ? 1 : 0;
    out_.no_fault_found += static_cast<std::int64_t>(u.no_fault_found.size());
    for (const auto& part : u.parts) out_.censored_records += part.withdrawn ? 1 : 0;
  }
  return absl::OkStatus();
}

void FillTruth(const Model& m, const Plan& plan, GeneratedFleet& out) {
  FleetTruth& truth = out.truth;
  truth.test_interval_days = static_cast<double>(plan.interval_us) / static_cast<double>(kMicrosPerDay);
  for (const auto& u : plan.units) {
    const std::string& batch = plan.batches[static_cast<std::size_t>(u.batch)].name;
    truth.batch_of_unit[u.serial] = batch;
    truth.analyses_of_unit[u.serial] = static_cast<std::int64_t>(u.tests.size());
    truth.fleet_operating_hours += u.end_hours;
    for (const auto& f : u.failures) {
      if (f.realised) {
        const auto month = internal::MicrosOfMonthStart(internal::YearMonthOf(f.time_us));
        ++truth.failures[{m.mode_models[static_cast<std::size_t>(f.mode)].id, batch, month}];
      } else if (!u.retired && !u.tests.empty() && f.time_us - u.tests.back().time_us < m.precursor_us &&
                 PrecursorShare(m, f.time_us - u.tests.back().time_us) >= 0.5) {
        truth.units_about_to_fail.insert(u.serial);
      }
    }
    for (const auto& t : u.tests) {
      ++truth.analyses[{batch, internal::MicrosOfMonthStart(internal::YearMonthOf(t.time_us))}];
    }
    for (const auto& part : u.parts) ++truth.parts_by_role[m.roles[static_cast<std::size_t>(part.role)]];
  }
  for (const auto& b : plan.batches) {
    for (std::size_t i = 0; i < m.identified.size(); ++i) {
      truth.ageing_per_year[{b.name, m.identified[i].name}] = b.ageing[i];
    }
  }
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
  const std::string name = absl::StartsWith(unit_type, "unitTypes/") ? unit_type.substr(10) : unit_type;
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
  if (auto s = options.Validate(); !s.ok()) return s;
  KnowledgeStore knowledge(pool);
  if (auto s = knowledge.Seed(api::BuiltinUnitTypes(), BuiltinFailureModeCatalogues()); !s.ok()) return s;
  auto db = pool.Acquire();
  if (!db.ok()) return db.status();
  auto roles = (*db)->Exec("SELECT role FROM module_roles ORDER BY role");
  if (!roles.ok()) return roles.status();
  std::vector<std::string> role_names;
  for (int r = 0; r < roles->rows(); ++r) role_names.push_back(roles->String(r, 0));
  auto model = BuildModel(options, role_names);
  if (!model.ok()) return model.status();
  const Model& m = *model;

  const auto start = std::chrono::steady_clock::now();
  Plan plan;
  const int units = options.units > 0 ? options.units : m.profile.units();
  if (units <= 0) return absl::InvalidArgumentError("the fleet needs at least one unit");
  PlanUnits(m, units, plan);
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
  PlanTests(m, plan, interval_us);
  progress(absl::StrCat("planned ", units, " units, ", plan.parts, " parts, ", plan.order.size(), " tests in ",
                        absl::StrFormat("%.1f", std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count()),
                        " s (test interval ", absl::StrFormat("%.1f", static_cast<double>(interval_us) / kMicrosPerDay),
                        " days)"));

  GeneratedFleet out;
  out.notes = m.notes;
  Writer writer(**db, m, plan, out, progress);
  if (auto s = (*db)->InTransaction([&] { return writer.WriteAll(); }); !s.ok()) return s;
  FillTruth(m, plan, out);
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
        return (*db)->ExecScript(
            "ANALYZE units, modules, runs, analyses, identified_parameters, effect_candidates, failure_records, "
            "diagnoses, diagnosis_candidates");
      });
      !s.ok()) {
    return s;
  }
  if (options.refine_signatures) {
    if (auto s = timed("refined the failure modes' signatures",
                       [&] { return knowledge.RefineSignatures(m.unit_type.name()); });
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
  return out;
}

}  // namespace insdiag::kb
